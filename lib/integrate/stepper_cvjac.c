/* CVODE BDF's difference-quotient Jacobian with small increments while a sliding contact's
 * slip speed is small (stepper.h, ap_step_jacobian_increment).
 *
 * CVODE differences column j of f's Jacobian with the increment max(sqrt(eps) |y_j|,
 * minInc / ewt_j), about 1.5e-8 |y_j|: 3e-7 rad/s for a wheel spinning at 20 rad/s, which
 * moves the wheel's contact slip by 5e-8 m/s. A sliding contact's friction acts along
 * s / |s|; while |s| is below that (just after a slip onset, or a slip that hovers near 0
 * with mu_kinetic = mu) the perturbed friction points anywhere and the column is wrong by a
 * factor |s| / |increment|: the Newton iteration with it fails and the steps fall to 1e-11 s
 * (the car after breakaway with mu_kinetic = mu, docs/vehicles.md). Here the relative
 * increment is rho (the driver's choice, a fraction of the smallest slip over the speed scale)
 * instead of sqrt(eps), with CVODE's formula otherwise:
 *     inc_j = max(rho |y_j|, minInc / ewt_j),  minInc = 1000 |h| eps n |f|_wrms (rho / sqrt(eps)),
 *     J_:j = (f(y + inc_j e_j) - f(y)) / inc_j.
 * The round-off of a column, eps |f| / inc_j, stays far below the entries that the friction's
 * 1/|s| makes large. Used only while rho < sqrt(eps); CVODE's own otherwise (bit for bit). */
#include <math.h>
#include <string.h>

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrate/stepper.h"

int ap_step_cv_jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *user, N_Vector tmp1,
                   N_Vector tmp2, N_Vector tmp3) {
  ap_stepper *s = user;
  int n = s->n;
  double *yv = N_VGetArrayPointer(y), *ewt = N_VGetArrayPointer(tmp2);
  double *ft = N_VGetArrayPointer(tmp1), rho = ap_step_jw_rho(s), h = 0.0;
  const double *f = N_VGetArrayPointer(fy);
  (void)tmp3;
  if (CVodeGetErrWeights(s->mem, tmp2) != CV_SUCCESS) return -1;
  CVodeGetCurrentStep(s->mem, &h);
  double fnorm = N_VWrmsNorm(fy, tmp2), eps = 2.220446049250313e-16;
  double min_inc = fnorm != 0.0 ? 1000.0 * fabs(h) * eps * n * fnorm * rho / sqrt(eps) : 1.0;
  for (int j = 0; j < n; j++) {
    double yj = yv[j], inc = fmax(rho * fabs(yj), min_inc / ewt[j]);
    yv[j] += inc;
    int rc = ap_step_rhs_eval(s, t, yv, ft);
    yv[j] = yj;
    if (rc != 0) return rc;
    double *col = SUNDenseMatrix_Column(J, j);
    for (int i = 0; i < n; i++) col[i] = (ft[i] - f[i]) / inc;
  }
  return 0;
}
