#!/usr/bin/env bash
# Where the tree path's instructions go, per disk per step: callgrind of bench_scaling's disks
# family at N disks over STEPS steps (uncounted warm-up), then the inclusive instructions of
# each stage's function (callgrind_annotate) divided by N x STEPS (docs/performance.md, "Tree
# path: instructions per disk per step"). Callgrind's call counts include the warm-up; the
# instruction counts do not, so only the latter are used.
#
#   bench/tree_profile.sh [N] [STEPS]      (default: 64 disks, 10 steps; keeps /tmp/tree_profile.N.cg;
#                                           REUSE=1: annotate that file again without running)
set -euo pipefail
n=${1:-64}
steps=${2:-10}
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cg=/tmp/tree_profile.$n.cg
[ -n "${REUSE:-}" ] || OPENBLAS_NUM_THREADS=1 valgrind --tool=callgrind --collect-atstart=no --callgrind-out-file="$cg" \
  build/bench/bench_scaling --callgrind disks "$n" "$steps" 2>/dev/null | grep '^callgrind'
annotate() { (cd / && callgrind_annotate --threshold=100 "$@" 2>/dev/null); }   # from / : one name per source file
annotate --inclusive=yes --tree=both "$cg" >"$cg.tree"
annotate --inclusive=yes "$cg" >"$cg.flat"
tot=$(grep -E '^(summary|totals):' "$cg" | head -n 1 | awk '{print $2}')
# inclusive Ir of a function (the flat listing), or of CALLEE called from CALLER (the tree)
incl() { { grep -E "^ *[0-9,]+ \([ 0-9.]+%\)  [^ ]*$1( |$)" "$cg.flat" || true; } | head -n 1 |
         awk '{gsub(",", "", $1); print $1 + 0}'; }   # (empty: not called, or below the listing)
from() { awk -v f="$1" -v c="$2" 'BEGIN { RS = "" } $0 ~ ("\\*  [^\n]*" f " ") {
           n = split($0, L, "\n"); for (i = 1; i <= n; i++) if (L[i] ~ (">   [^ ]*" c " ")) {
             split(L[i], w, " "); gsub(",", "", w[1]); print w[1]; exit } }' "$cg.tree"; }
per() { echo $(( ${1:-0} / (n * steps) )); }
rhs=$(incl 'sim_step.c:ap_drv_rhs'); after=$(incl 'sim_after.c:ap_drv_after_step'); after=${after:-0}
apos=$(from 'sim_step.c:ap_drv_stage_partition' 'forward.c:ap_fwd_position')
pos=$(incl 'structured.c:ap_st_position')
printf '%-62s %9s\n' "stage (Ir per disk per step, N = $n)" Ir
row() { printf '%-62s %9d\n' "$1" "$(per "$2")"; }
row "total" "$tot"
row "evaluations by the stepper (ap_step_rhs_eval)" "$(incl 'stepper.c:ap_step_rhs_eval')"
row "output evaluation (ap_drv_evaluate_current)" "$(incl 'sim_step.c:ap_drv_evaluate_current')"
row "  all evaluations: ap_forward" "$(incl 'core/forward.c:ap_forward')"
row "    position stage (without the after-step one)" "$((pos - ${apos:-0}))"
row "    velocity stage (ap_st_velocity)" "$(incl 'structured.c:ap_st_velocity')"
row "    acceleration stage (ap_st_acceleration)" "$(incl 'structured.c:ap_st_acceleration')"
row "after-step work (ap_drv_after_step)" "$after"
row "  of it the position stage (partition check)" "${apos:-0}"
row "stepper (ARKODE: vector ops, norms, interpolation; the rest)" "$((tot - rhs - after))"
row "  N_VLinearCombination" "$(incl 'N_VLinearCombination')"
row "position stage, all calls (ap_st_position)" "$pos"
row "  kinematics, geometry, rows (tree_eval.c objects)" "$(incl 'tree_eval.c:objects')"
row "    ap_kin_position" "$(incl 'kinematics.c:ap_kin_position')"
row "    ap_tree_geometry" "$(incl 'tree_eval.c:ap_tree_geometry')"
row "    contact rows (contact_tree_row)" "$(incl 'contact.c:contact_tree_row')"
row "  tree factorisation (ap_la_comp_factor)" "$(incl 'tree_comp.c:ap_la_comp_factor')"
row "    per-tree partition and basis (ap_la_partition_basis)" "$(incl 'nullspace.c:ap_la_partition_basis')"
row "velocity sweeps (ap_tree_velocity)" "$(incl 'tree_eval.c:ap_tree_velocity')"
row "finiteness checks (ap_core_check_finite, exclusive)" \
  "$(annotate "$cg" | grep -E 'forward.c:ap_core_check_finite( |$)' | head -n 1 |
      awk '{gsub(",", "", $1); print $1}')"
