#!/usr/bin/env python3
"""bench/run's BENCHMARKS.md writer: regenerating a table replaces only its generated part (between
`<!-- table: NAME -->` and `<!-- end table: NAME -->`); hand-written text after an end marker, and every
table not regenerated, stay byte for byte. Before, a full run rewrote each section whole and deleted the
issue sections written by hand below the tables.
  bench_run_merge_test.py PROJECT_SOURCE_DIR"""
import sys
from importlib.machinery import SourceFileLoader

root = sys.argv[1]
bench_run = SourceFileLoader("bench_run", f"{root}/bench/run").load_module()
names = ["paper-table1", "cameras", "objects", "detector-accuracy", "components"]
old = open(f"{root}/BENCHMARKS.md").read()
failures = []

before = bench_run.split_sections(old)
for name in names:
    if name not in before:
        failures.append(f"BENCHMARKS.md: table {name} has no '<!-- table: {name} -->' marker")
    elif f"<!-- end table: {name} -->" not in old:
        failures.append(f"BENCHMARKS.md: table {name} has no end marker: its hand-written text would be lost")

# Every table regenerated at once (a full bench/run): only the generated parts change.
new = bench_run.merge_sections(old, {n: f"NEW {n}" for n in names}, names, "test machine")
after = bench_run.split_sections(new)
for name in names:
    if after[name][0] != f"NEW {name}":
        failures.append(f"table {name}: generated part not replaced")
    if after[name][1] != before.get(name, ("", ""))[1]:
        failures.append(f"table {name}: hand-written text after the end marker changed")

# One table regenerated: every other table is kept as it was.
one = bench_run.split_sections(bench_run.merge_sections(old, {"cameras": "NEW"}, names, "test machine"))
for name in names:
    if name != "cameras" and one[name] != before[name]:
        failures.append(f"--only cameras changed table {name}")

# The components table runs the bench_* programs only: build/bench's diag_* diagnostics (some need
# arguments; one printed 10000 lines) are not benchmarks.
listing = ["bench_core", "diag_side_bias", "bench_accuracy", "CMakeFiles", "bench_detector", "diag_hard",
           "bench_imaging_maps", "Makefile"]
if bench_run.component_benches(listing) != ["bench_core", "bench_detector"]:
    failures.append(f"components would run {bench_run.component_benches(listing)}")

# Idempotent: merging nothing gives the same tables back.
same = bench_run.split_sections(bench_run.merge_sections(old, {}, names, "test machine"))
if same != before:
    failures.append("merging no new table changed the file's tables")

for f in failures:
    print("FAIL:", f)
print("bench/run merge:", "ok" if not failures else f"{len(failures)} failures")
sys.exit(1 if failures else 0)
