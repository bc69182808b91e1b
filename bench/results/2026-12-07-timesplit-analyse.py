# timesplit: joins the timer tables with callgrind's per-function counts (2026-12-07-timesplit.md).
# Run in a directory holding: ts1.txt.. (bench_detector 60 2 640 output of the timer build, accurate only),
# fine1.txt.. (the same with MCMT_TIMESPLIT_FINE=1), and cgts.incl.txt / cgts.self.txt / cgts.tree.txt:
#   callgrind_annotate --inclusive=yes|no [--tree=caller] --threshold=100
#     --show=Ir,I1mr,D1mr,D1mw,ILmr,DLmr,DLmw,Bc,Bcm,Bi,Bim cgts.out
# of the callgrind run on the same timer build (command in the write-up). Prints the write-up's tables.
import re, statistics, glob
EV = ['Ir','I1mr','D1mr','D1mw','ILmr','DLmr','DLmw','Bc','Bcm','Bi','Bim']
NUM = r'((?:\s*[\d,]+(?:\s*\(\s*[\d\.]+%\))?|\s*\.)+)'
def nums(s):
    s = re.sub(r'\(\s*[\d\.]+%\)', ' ', s)
    v = s.split()
    try:
        return [0 if x == '.' else int(x.replace(',', '')) for x in v]
    except ValueError:
        return []
def parse_flat(path):
    d = {}
    for line in open(path):
        m = re.match(r'^(.*?)\s+(\?\?\?:|\./|/)(.*)$', line.rstrip('\n'))
        if not m: continue
        v = nums(m.group(1))
        if len(v) != len(EV): continue
        d[m.group(2) + m.group(3)] = dict(zip(EV, v))
    return d
def parse_tree(path):
    edges = {}  # (callee, caller) -> vals
    block = []
    for line in open(path):
        m = re.match(r'^(.*?)\s+([<>*])\s+(.*)$', line.rstrip('\n'))
        if not m:
            block = []; continue
        v = nums(m.group(1))
        if len(v) != len(EV): continue
        name = re.sub(r' \([\d,]+x\)', '', m.group(3))
        if m.group(2) == '<': block.append((name, dict(zip(EV, v))))
        elif m.group(2) == '*':
            for caller, vals in block: edges[(name, caller)] = vals
            block = []
    return edges
incl = parse_flat('cgts.incl.txt'); excl = parse_flat('cgts.self.txt'); edges = parse_tree('cgts.tree.txt')
def pick(d, pat, one=False):
    hits = [n for n in d if re.search(pat, n)]
    assert hits, pat
    if one: assert len(hits) == 1, (pat, hits)
    return {e: sum(d[n][e] for n in hits) for e in EV}
def edge(callee_pat, caller_pat):
    hits = [k for k in edges if re.search(callee_pat, k[0]) and re.search(caller_pat, k[1])]
    assert hits, (callee_pat, caller_pat)
    return {e: sum(edges[k][e] for k in hits) for e in EV}
def add(*xs): return {e: sum(x[e] for x in xs) for e in EV}
def sub(a, *xs): return {e: a[e] - sum(x[e] for x in xs) for e in EV}
I = lambda p: pick(incl, p, True)
X = lambda p: pick(excl, p, True)
# timers
runs = []
for f in sorted(glob.glob('ts[0-9]*.txt')):
    t = {}
    for line in open(f):
        m = re.match(r'^\| (.+?) \| ([\d\.]+) \| ([\d\.]+) \| ([\d\.]+) \| ([\d\.]+) \|$', line.rstrip())
        if m: t[m.group(1).strip()] = (float(m.group(2)), float(m.group(3)), float(m.group(4)))
    runs.append(t)
def T(name, col):  # col 1 incl, 2 self; median over runs
    return statistics.median(r[name][col] for r in runs)
images = 120
detect = I(r'MarkerDetector::Detect\(')
thr = I(r'cv::adaptiveThreshold\(')
fwc = I(r'FindWindowCandidates')
cont = pick(incl, r'bench_detector\]$' if False else r'^\?\?\?:cv::findContours\(cv::_InputArray const&, cv::_OutputArray const&, int, int, cv::Point_<int>\) \[/work')
group = add(I(r'KeepLargestOfGroups'), I(r'MakeClockwise'))
ident = I(r'IdentifyCandidate')
reread_all = add(I(r'MarkerDetector::RereadCandidate'), I(r'MarkerDetector::SearchInsideRejected'))
rmc_in_reread = edge(r'RefineMarkerCorners\(cv', r'RereadCandidate|SearchInsideRejected')
full = I(r'MarkerDetector::FullSearch')
drop = add(I(r'MarkerDetector::DropDuplicates'), I(r'MarkerDetector::DropLookAlikes'))
smooth = add(I(r'^\?\?\?:cv::GaussianBlur\('), I(r'MarkerDetector::RefineRegion'))
rmc = I(r'^\?\?\?:mcmt::RefineMarkerCorners\(cv::Mat const&, int, cv::Mat const&, mcmt::CameraModel const\*, int, std::array<cv::Point_<double>, 4ul>\*, bool, double\*, bool, bool\*, int, double\) \[')
sample = I(r'::SampleSide\(')
cross = I(r'::CrossingLine\(')
cfl = I(r'::CornersFromLines\(')
rays = I(r'::CollectSideRays\(')
prof = pick(incl, r'SideRays::SampleProfiles')
fsp = I(r'mcmt::FitSideProfiles\(')
ev = pick(incl, r'avx2::Evaluate\(mcmt::SideProfiles[^{]*$')
fill = pick(incl, r'avx2::FillBoundaryLanes')
bs = I(r'BoundedStep')
paper = I(r'MarkerPaperLevel')
detrend_self = sub(I(r'mcmt::DetrendSurround'), edge(r'mcmt::FitSideProfiles\(', r'DetrendSurround'))
turn_self = sub(I(r'::TurnSide\('), edge(r'mcmt::FitSideProfiles\(', r'::TurnSide\('), edge(r'SideRays::SampleProfiles', r'::TurnSide\('))
judge = edge(r'CodeMismatches', r'RefineCorners')
rows = [
 ('search: adaptiveThreshold', T('adaptiveThreshold', 2), thr),
 ('search: findContours', T('findContours', 2), cont),
 ('search: approxPolyDP, checks', T('approxPolyDP etc', 2), sub(fwc, cont)),
 ('search: group candidates', T('group candidates', 2), group),
 ('search: identify (warp, bits)', T('identify (warp, bits)', 2), ident),
 ('search: reread rejected (less its refinement)', T('reread rejected', 2), sub(reread_all, rmc_in_reread)),
 ('search: other (setup, copies)', T('search (FullSearch)', 2), sub(full, thr, fwc, group, ident, reread_all)),
 ('drop duplicates', T('drop duplicates', 2), drop),
 ('smoothed region image (GaussianBlur)', T('smoothed region image', 1), smooth),
 ('refine: SampleSide (crossing samples)', T('SampleSide', 2), sample),
 ('refine: CrossingLine', T('CrossingLine', 2), cross),
 ('refine: CollectSideRays', T('CollectSideRays', 2), rays),
 ('refine: SampleProfiles (bilinear samples into bins)', T('SampleProfiles', 2), prof),
 ('refine: Evaluate (model, Jacobian, normal eqs)', T('Evaluate', 2), ev),
 ('refine: BoundedStep (Cholesky, bounds)', T('BoundedStep', 2), bs),
 ('refine: FitSideProfiles/FitOnce rest', T('FitSideProfiles', 2), sub(fsp, ev, bs)),
 ('refine: DetrendSurround + TurnSide (own)', T('DetrendSurround', 2) + T('TurnSide', 2), add(detrend_self, turn_self)),
 ('refine: paper level + CornersFromLines', T('paper level', 2) + T('CornersFromLines', 2), add(paper, cfl)),
]
leaf_ir = add(sample, cross, rays, prof, fsp, detrend_self, turn_self, paper, cfl)
rows.append(('refine: other (RefineOnce, LocateSide, FitSide glue)',
             T('RefineMarkerCorners', 2) + T('first RefineOnce', 2) + T('model rounds', 2) + T('skew pass', 2),
             add(*[pick(excl, p) for p in (r'RefineOnce', r'RefinePass', r'FitWholeSide', r'RefineMarkerCorners', r'TurnSkewedSides')])))
rows.append(('judge code (RefineCorners)', T('judge code', 1), judge))
used = add(*[r[2] for r in rows])
# timers: rest = total - sum
total_ms = T('Detect (total)', 1)
rows.append(('rest (Detect glue, gray, tone, ...)', total_ms - sum(r[1] for r in rows), sub(detect, used)))
def model(v):
    return v['Ir'] + 10 * (v['I1mr'] + v['D1mr'] + v['D1mw']) + 100 * (v['ILmr'] + v['DLmr'] + v['DLmw']) + 15 * (v['Bcm'] + v['Bim'])
tot_model = model(detect)
tick_per_ms = 2599.8e3
print('| step | ms/image | % time | M instr/image | % instr | ticks/instr | model M cycles/image | % model | mispredicts k/image | mispredict rate % | L1 misses k/image |')
print('|---|---|---|---|---|---|---|---|---|---|---|')
for name, ms, v in rows + [('**total (Detect)**', total_ms, detect)]:
    ir = v['Ir'] / images / 1e6
    br = (v['Bc'] + v['Bi'])
    print('| %s | %.3f | %.1f | %.2f | %.1f | %.2f | %.2f | %.1f | %.1f | %.1f | %.1f |' % (
        name, ms, 100 * ms / total_ms, ir, 100 * v['Ir'] / detect['Ir'], ms * tick_per_ms / (v['Ir'] / images) if v['Ir'] > 0 else float('nan'),
        model(v) / images / 1e6, 100 * model(v) / tot_model, (v['Bcm'] + v['Bim']) / images / 1e3,
        100 * (v['Bcm'] + v['Bim']) / br if br else 0, (v['I1mr'] + v['D1mr'] + v['D1mw']) / images / 1e3))
print()
print('FillBoundaryLanes (inside Evaluate): M instr/image %.2f, model %.2f, mispred k %.1f' % (fill['Ir']/images/1e6, model(fill)/images/1e6, (fill['Bcm']+fill['Bim'])/images/1e3))
ev_self = pick(excl, r'avx2::Evaluate\(mcmt::SideProfiles[^{]*$')
print('Evaluate exclusive M instr/image %.2f' % (ev_self['Ir']/images/1e6))
# phases
first = edge(r'RefineOnce', r'^\?\?\?:mcmt::RefineMarkerCorners\(cv::Mat const&, int, cv::Mat const&, mcmt::CameraModel const\*, int, std::array<cv::Point_<double>, 4ul>\*, bool, double\*, bool, bool\*, int, double\) \[')
rounds = edge(r'RefineOnce', r'lambda')
skew = pick(incl, r'TurnSkewedSides')
print('\n| phase | ms/image (incl) | M instr/image | ticks/instr |\n|---|---|---|---|')
for name, ms, v in [('first RefineOnce (narrow/wide)', T('first RefineOnce', 1), first), ('model rounds (RefineOnce model_only)', T('model rounds', 1), rounds), ('skew pass (TurnSkewedSides)', T('skew pass', 1), skew), ('RefineMarkerCorners (all)', T('RefineMarkerCorners', 1), rmc), ('search (FullSearch)', T('search (FullSearch)', 1), full)]:
    print('| %s | %.3f | %.2f | %.2f |' % (name, ms, v['Ir']/images/1e6, ms*tick_per_ms/(v['Ir']/images)))
print('\ncalls per image (timers):', {k: runs[0][k][0] for k in runs[0]})
# fine split inside Evaluate and BoundedStep (separate runs with MCMT_TIMESPLIT_FINE=1)
fruns = []
for f in sorted(glob.glob('fine[0-9]*.txt')):
    t = {}
    for line in open(f):
        m = re.match(r'^\| (.+?) \| ([\d\.]+) \| ([\d\.]+) \| ([\d\.]+) \| ([\d\.]+) \|$', line.rstrip())
        if m: t[m.group(1).strip()] = (float(m.group(2)), float(m.group(3)), float(m.group(4)))
    fruns.append(t)
F = lambda name, col: statistics.median(r[name][col] for r in fruns)
normal = pick(incl, r'avx2::NormalRowPair<')
chol = I(r'mcmt::CholeskyLower')
print('\nfine runs: Detect %.3f ms, Evaluate incl %.3f ms (vs %.3f without fine timers)' % (F('Detect (total)', 1), F('Evaluate', 1), T('Evaluate', 1)))
print('| inside the side fit | calls/image | ms/image (fine runs) | M instr/image | ticks/instr | mispredicts k/image |\n|---|---|---|---|---|---|')
for name, key, v in [('FillBoundaryLanes', 'FillBoundaryLanes (fine)', fill), ('NormalEquations (NormalRowPair)', 'NormalEquations (fine)', normal),
                     ('Evaluate own (bins, model, Jacobian rows)', 'Evaluate', sub(ev, fill, normal)), ('CholeskyLower', 'CholeskyLower (fine)', chol),
                     ('BoundedStep own (bounds, solve)', 'BoundedStep', sub(bs, chol))]:
    ms = F(key, 2)
    print('| %s | %.1f | %.3f | %.2f | %.2f | %.1f |' % (name, fruns[0][key][0], ms, v['Ir']/images/1e6, ms*tick_per_ms/(v['Ir']/images), (v['Bcm']+v['Bim'])/images/1e3))
