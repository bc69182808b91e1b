#!/usr/bin/env bash
# mcmt-report's page in headless Chromium: a mapper output folder -> report.html, loaded from file://
# with no server; asserts the page loads, every image decodes (naturalWidth > 0), the page makes no
# request beyond itself and logs nothing on the console. Optionally saves a screenshot.
#   report_page_test.sh BIN_DIR MAP_OUTDIR WORK_DIR [SCREENSHOT.png]
# Exit 77: skipped (no chromium, or the input folder is absent).
set -euo pipefail
BIN="$1"; MAPDIR="$2"; WORK="$3"; SHOT="${4:-}"
CHROMIUM="$(command -v chromium || command -v chromium-browser || true)"
[[ -n "$CHROMIUM" ]] || { echo "report_page_test: SKIP: no chromium (scripts/setup installs it)"; exit 77; }
[[ -s "$MAPDIR/map.yaml" ]] || { echo "report_page_test: SKIP: $MAPDIR/map.yaml absent"; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK"
cp -r "$MAPDIR" "$WORK/map"
"$BIN/mcmt-report" "$WORK/map" >"$WORK/report.txt" 2>&1 || { cat "$WORK/report.txt"; echo "report_page_test: FAIL: mcmt-report"; exit 1; }
PAGE="$WORK/map/report.html"
[[ -s "$PAGE" ]] || { echo "report_page_test: FAIL: no $PAGE"; exit 1; }
if grep -Eq '(src|href)="(https?:|file:|//)' "$PAGE"; then echo "report_page_test: FAIL: external reference"; exit 1; fi
# A copy of the page with a probe first in <head>: it records errors, and after load writes the images'
# naturalWidth into the DOM, which --dump-dom prints.
python3 - "$PAGE" "$WORK/probe.html" <<'PY'
import sys
page = open(sys.argv[1]).read()
probe = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push(String(e.message || e.type)), true);
window.addEventListener('load', () => {
  const w = Array.from(document.images).map(i => i.complete ? i.naturalWidth : 0);
  const p = document.createElement('pre'); p.id = 'probe';
  p.textContent = 'PROBE ' + JSON.stringify({images: w, errors: window.__errors});
  document.body.appendChild(p);
});
</script>"""
open(sys.argv[2], "w").write(page.replace("<head>", "<head>" + probe, 1))
PY
FLAGS=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --disable-extensions --enable-logging=stderr --v=0)
timeout 120 "$CHROMIUM" "${FLAGS[@]}" --user-data-dir="$WORK/profile" --virtual-time-budget=5000 \
  --dump-dom "file://$WORK/probe.html" >"$WORK/dom.html" 2>"$WORK/chromium.log" || true
python3 - "$WORK/dom.html" "$WORK/chromium.log" "$PAGE" <<'PY'
import html, json, re, sys
dom, log, page = (open(p, errors="replace").read() for p in sys.argv[1:4])
m = re.search(r"PROBE (\{.*?\})</pre>", dom)
if not m:
    print("report_page_test: FAIL: the page did not finish loading (no probe in the DOM)"); sys.exit(1)
r = json.loads(html.unescape(m.group(1)))
expected = page.count("<img ")
console = [l for l in log.splitlines() if "CONSOLE" in l]
print(f"images: {len(r['images'])} (page has {expected}), widths {r['images']}")
ok = len(r["images"]) == expected and expected > 0 and all(w > 0 for w in r["images"])
if r["errors"] or console:
    print("errors:", r["errors"], console[:5]); ok = False
print("report_page_test:", "PASS" if ok else "FAIL")
sys.exit(0 if ok else 1)
PY
if [[ -n "$SHOT" ]]; then
  timeout 120 "$CHROMIUM" "${FLAGS[@]}" --user-data-dir="$WORK/profile2" --hide-scrollbars --window-size=1280,1600 \
    --screenshot="$SHOT" "file://$PAGE" >/dev/null 2>&1 || true
  [[ -s "$SHOT" ]] && echo "screenshot: $SHOT"
fi
exit 0
