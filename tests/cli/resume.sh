#!/usr/bin/env bash
# A run that ends writes OUT/checkpoint.bin; running the same case for longer with --resume
# continues it: the series keeps its earlier rows, continues to the new duration with
# increasing steps, and the frame series lists every frame once. (Bitwise continuation from
# a mid-run checkpoint is tested in tests/unit/test_checkpoint.cpp.)
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
args="--set insert.0.count=200 --set output.frame_interval=0.001 --quiet"
"$bin" run "$src/examples/box_pour.toml" $args --set simulation.duration=0.002 --out "$work/o" > /dev/null 2>&1 || { echo "FAIL first run"; exit 1; }
rows1=$(($(wc -l < "$work/o/series.csv") - 1))
"$bin" run "$src/examples/box_pour.toml" $args --set simulation.duration=0.004 --out "$work/o" --resume "$work/o/checkpoint.bin" > "$work/log" 2>&1 || { echo "FAIL resume"; cat "$work/log"; exit 1; }
python3 - "$work/o" "$rows1" <<'PY'
import csv, sys, re
out, rows1 = sys.argv[1], int(sys.argv[2])
rows = list(csv.DictReader(open(out + "/series.csv")))
steps = [int(float(r["step"])) for r in rows]
ok = True
if steps != sorted(set(steps)): print("FAIL steps not strictly increasing"); ok = False
if len(rows) <= rows1: print("FAIL no rows added"); ok = False
if abs(float(rows[-1]["time"]) - 0.004) > 2e-6: print("FAIL last time", rows[-1]["time"]); ok = False
files = re.findall(r'file="([^"]+)"', open(out + "/particles.pvd").read())
if len(files) != len(set(files)) or len(files) < 5: print("FAIL frames", files); ok = False
print("1 passed, 0 failed" if ok else "0 passed, 1 failed")
sys.exit(0 if ok else 1)
PY
