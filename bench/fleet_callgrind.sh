#!/usr/bin/env bash
# Instructions per step of bench_fleet's robots (N differential-drive robots, every fourth with a
# trailer) on the path auto chooses (the tree path: k >= 16), counted by callgrind over STEPS
# steps after an uncounted warm-up; writes OUT.csv (N,k,path,steps,evals,partitions,Ir,
# Ir_per_step,Ir_per_robot_step) and prints the fitted exponent of Ir per step against N.
# Load-independent, unlike bench_fleet's CPU times (docs/performance.md).
#
#   bench/fleet_callgrind.sh OUT.csv [STEPS] [N...]     (default: 10 steps, N = 16 32 64 128 256)
# (PATH_ARG=dense in the environment: the dense path)
set -euo pipefail
out=${1:?usage: bench/fleet_callgrind.sh OUT.csv [STEPS] [N...]}
steps=${2:-10}
shift $(($# >= 2 ? 2 : 1))
ns=("$@")
((${#ns[@]})) || ns=(16 32 64 128 256)
cd "$(dirname "${BASH_SOURCE[0]}")/.."
exe=build/bench/bench_fleet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "N,k,path,steps,evals,partitions,Ir,Ir_per_step,Ir_per_robot_step" >"$out"
for n in "${ns[@]}"; do
  line=$(OPENBLAS_NUM_THREADS=1 nice valgrind --tool=callgrind --collect-atstart=no \
    --callgrind-out-file="$tmp/cg" "$exe" --path "${PATH_ARG:-auto}" --callgrind "$n" "$steps" \
    2>/dev/null | grep '^callgrind')
  ir=$(grep -E '^(summary|totals):' "$tmp/cg" | head -n 1 | awk '{print $2}')
  # callgrind fleet N n k K path P steps S evals E partitions W
  read -r _ _ _ _ _ k _ path _ st _ ev _ pw <<<"$line"
  echo "$n,$k,$path,$st,$ev,$pw,$ir,$((ir / st)),$((ir / st / n))" | tee -a "$out"
done
/usr/bin/python3 - "$out" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
pts = [(math.log(int(r["N"])), math.log(float(r["Ir_per_step"]))) for r in rows]
if len(pts) >= 2:
    n = len(pts); sx = sum(x for x, _ in pts); sy = sum(y for _, y in pts)
    sxx = sum(x * x for x, _ in pts); sxy = sum(x * y for x, y in pts)
    p = (n * sxy - sx * sy) / (n * sxx - sx * sx)
    print(f"fleet: instructions per step ~ N^{p:.3f} over N = " + ", ".join(r["N"] for r in rows))
PY
