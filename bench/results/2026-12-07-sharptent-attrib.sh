#!/bin/bash
# The one-side fit's outward offset on small cells, attributed (sharptent, 2026-12-07): diag_side_exact's
# SWEEP (the fit with the line at the truth, averaged over ids 0 .. IDS-1 x sides 0-3 and pixel phases, per
# roll 13 / 37 / 58 / 77 deg) with each suspect of the profiles switched off. Prints one line per row:
# blur, side px, row, the mean over the four rolls and each roll's.
# usage: bash 2026-12-07-sharptent-attrib.sh "BLURS" "SIDES" "ROWS"   (defaults below)
EXE=${EXE:-build/bench/diag_side_exact}
IDS=${IDS:-16}
BLURS=${1:-0.01}
SIDES=${2:-9 12 16 20}
ROWS=${3:-head quant0 gamma0 phaseavg box gauss gaussbox du half rays8 rowcap3 tent}
T=$(mktemp -d)
python3 -c "
for j in range(8):
  for i in range(8): print('%.4f %.4f' % ((i + 0.5) / 8, (j + 0.5) / 8))" > "$T/ph64"
echo "0.3 0.7" > "$T/ph1"
for blur in $BLURS; do for side in $SIDES; do for row in $ROWS; do
  # The Gaussian of the pixel's variance (box 4 x 4 and the bilinear tent) and the blur: the model exact.
  eq=$(python3 -c "print('%.6f' % (($blur ** 2 + 1 / 6 + (1 - 1 / 16) / 12) ** 0.5))")
  case $row in
    head) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    quant0) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 QUANT=0 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    gamma0) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 FITGAMMA=0 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    phaseavg) out=$(SWEEP=$T/ph1 PIX=1 BOX=4 PHASEAVG=8 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    box) out=$(SWEEP=$T/ph1 PIX=1 BOX=4 NOTENT=1 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    gauss) out=$(SWEEP=$T/ph1 "$EXE" "$IDS" -1 "$eq" "$side") ;;
    gaussbox)  # the Gaussian of the box's variance alone and the blur: NOTENT's (box) control
      eqbox=$(python3 -c "print('%.6f' % (($blur ** 2 + (1 - 1 / 16) / 12) ** 0.5))")
      out=$(SWEEP=$T/ph1 "$EXE" "$IDS" -1 "$eqbox" "$side") ;;
    du) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 DU=0.5 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    half) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 DU=0.5 RAYS=8 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    rays8) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 RAYS=8 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    rowcap3) out=$(SWEEP=$T/ph64 PIX=1 BOX=4 ROWCAP=3 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    tent) out=$(SWEEP=$T/ph64 PIX=1 BOX=1 "$EXE" "$IDS" -1 "$blur" "$side") ;;
    *) echo "unknown row $row"; continue ;;
  esac
  echo "$out" | awk -v b="$blur" -v s="$side" -v r="$row" '
    /^roll/ {v = v sprintf(" %s", $5); if ($12 + 0 > 0 || $13 + 0 > 0) f = f " failed:" $12}
    /^all/ {m = $3}
    END {printf "blur %s side %s %-9s %s  rolls%s%s\n", b, s, r, m, v, f}'
done; done; done
rm -rf "$T"
