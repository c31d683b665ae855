#!/usr/bin/env bash
# Instructions per step of bench_scaling's two families on the path auto chooses (the tree path
# from N = 64 on), counted by callgrind over STEPS steps after an uncounted warm-up; writes
# OUT.csv (family,N,k,path,steps,evals,Ir,Ir_per_step) and prints the fitted exponent of
# Ir per step against N. Load-independent, unlike bench_scaling's CPU times (docs/performance.md).
#
#   bench/scaling_callgrind.sh OUT.csv [STEPS] [N...]     (default: 10 steps, N = 64 256 1024 4096 10000)
# (FAMILIES="disks" in the environment: one family only)
set -euo pipefail
out=${1:?usage: bench/scaling_callgrind.sh OUT.csv [STEPS] [N...]}
steps=${2:-10}
shift $(($# >= 2 ? 2 : 1))
ns=("$@")
((${#ns[@]})) || ns=(64 256 1024 4096 10000)
cd "$(dirname "${BASH_SOURCE[0]}")/.."
exe=build/bench/bench_scaling
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "family,N,k,path,steps,evals,Ir,Ir_per_step" >"$out"
for fam in ${FAMILIES:-trailers disks}; do
  for n in "${ns[@]}"; do
    line=$(OPENBLAS_NUM_THREADS=1 valgrind --tool=callgrind --collect-atstart=no \
      --callgrind-out-file="$tmp/cg" "$exe" --callgrind "$fam" "$n" "$steps" 2>/dev/null |
      grep '^callgrind')
    ir=$(grep -E '^(summary|totals):' "$tmp/cg" | head -n 1 | awk '{print $2}')
    read -r _ _ _ _ _ k _ path _ st _ ev <<<"$line"   # callgrind F N n k K path P steps S evals E
    echo "$fam,$n,$k,$path,$st,$ev,$ir,$((ir / st))" | tee -a "$out"
  done
done
/usr/bin/python3 - "$out" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for fam in ("trailers", "disks"):
    pts = [(math.log(int(r["N"])), math.log(float(r["Ir_per_step"]))) for r in rows if r["family"] == fam]
    if len(pts) < 2:
        continue
    n = len(pts); sx = sum(x for x, _ in pts); sy = sum(y for _, y in pts)
    sxx = sum(x * x for x, _ in pts); sxy = sum(x * y for x, y in pts)
    p = (n * sxy - sx * sy) / (n * sxx - sx * sx)
    print(f"{fam}: instructions per step ~ N^{p:.3f} over N = "
          + ", ".join(r["N"] for r in rows if r["family"] == fam))
PY
