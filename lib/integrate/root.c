/* One root finder for every crossing located on a stepper's dense output: the events
 * (event.c, locate) and the loop-rank monitor's sign change of a minor of A (sim_rank.c).
 *
 * Illinois-modified regula falsi (Dowell and Jarratt 1971): the secant of the bracket's ends,
 * and the value kept at an end that stays twice in a row halved, so that the bracket shrinks
 * from both sides; a bisection whenever a step fails to halve the bracket's width, so the
 * width at least halves every two evaluations. The invariant: fn is on the old side at ta and
 * not on it at tb. Which side a value of exactly 0 is on is the caller's (zero): for an event
 * 0 is the side entered (a value 0 at the step's end counts as a crossing), for the sign of a
 * determinant 0 is the negative side. */
#include "integrate/root.h"

#include <float.h>
#include <math.h>

#include "appell/status.h"

/* g is on the old side (+1 or -1). */
static int on_old_side(int old, ap_drv_root_zero zero, double g) {
  if (g == 0.0) return zero == AP_ROOT_ZERO_NEGATIVE && old < 0;
  return old > 0 ? g > 0 : g < 0;
}

int ap_drv_root_locate(ap_drv_root_fn fn, void *ctx, int old, ap_drv_root_zero zero, int iter,
                       double ta, double ga, double tb, double gb, double *troot) {
  double width = tb - ta;
  int side = 0, bisect = 0;
  for (int it = 0; it < iter && gb != 0.0; it++) {
    if (tb - ta <= 4.0 * DBL_EPSILON * fmax(fabs(ta), fabs(tb))) break;
    double tm = bisect || gb == ga ? 0.5 * (ta + tb) : tb - gb * (tb - ta) / (gb - ga);
    if (!(tm > ta && tm < tb)) tm = ta + 0.5 * (tb - ta);
    if (!(tm > ta && tm < tb)) break;             /* no float between them */
    double gm = 0.0;
    int rc = fn(ctx, tm, &gm);
    if (rc != AP_OK) return rc;
    if (on_old_side(old, zero, gm)) {
      ta = tm, ga = gm;
      if (side == -1) gb *= 0.5;
      side = -1;
    } else {
      tb = tm, gb = gm;
      if (side == 1) ga *= 0.5;
      side = 1;
    }
    bisect = tb - ta > 0.5 * width;
    width = tb - ta;
  }
  *troot = tb;
  return AP_OK;
}
