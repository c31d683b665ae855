/* Error control where it matters: coordinates that nothing else depends on, and the stepper's
 * error weights that leave them out of the step-size control (include/appell/accuracy.h).
 *
 * A coordinate q_i is free when no component of the state's derivative outside a set S of
 * coordinates depends on it, S holding q_i itself and other free coordinates only: a ball's
 * orientation on a turntable (q' = N(q) v for the quaternion depends on the quaternion and the
 * speeds, but neither the speeds' derivatives nor the position's rates depend on it). Such a
 * coordinate cannot change the rest of the solution, so its own error need not limit the step.
 * Found numerically, like the linearizer's cyclic coordinates (lib/analyze): the right-hand
 * side is evaluated at the current state and at a second state moved by 1e-3 of each entry's
 * size (both in the mode's own variables), each coordinate perturbed by 1e-4 of its size; a
 * component counts as depending on q_i when it moved by more than 1e-10 of its size (and
 * 1e-13 of the largest rate), far above round-off (1e-16) and far below a real dependence of
 * relative strength 1e-5. S is then shrunk to a fixed point. A simulation with events has no
 * free coordinate (an event function may read any). Outputs are not seen here: the caller
 * keeps the coordinates they ask for (ap_sim_set_uncontrolled).
 *
 * Weights: s->wt (ny) is 1 for every state entry and 0 for an uncontrolled coordinate; the
 * stepper reads it at every step (ap_step_opts.weight). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "appell/accuracy.h"
#include "integrate/sim_int.h"

/* Made at creation and made again with the stepper when a contact-mode switch changes the
 * number of free speeds: the coordinates' weights (the first n, set by
 * ap_sim_set_uncontrolled) are kept, the speeds' are 1. */
int ap_drv_weights_create(ap_sim *s, size_t ny) {
  double *w = malloc(sizeof(double) * (ny ? ny : 1));
  if (!w) return AP_ERR_NOMEM;
  for (size_t i = 0; i < ny; i++) w[i] = s->wt && i < (size_t)s->n ? s->wt[i] : 1.0;
  free(s->wt);
  s->wt = w;
  return AP_OK;
}

/* dep[i * ny + j] = 1 when f_j moves with y_i (i < n) at the state y (ny); f0, f1, y1 scratch. */
static int dependencies(ap_sim *s, double t, const double *y, unsigned char *dep, double *f0,
                        double *f1, double *y1) {
  int n = s->n, ny = s->ny;
  if (ap_drv_rhs(t, y, f0, s) != 0) return s->rhs_status ? s->rhs_status : AP_ERR_SOLVER;
  double fmax_ = 0.0;
  for (int j = 0; j < ny; j++) fmax_ = fmax(fmax_, fabs(f0[j]));
  for (int i = 0; i < n; i++) {
    memcpy(y1, y, sizeof(double) * (size_t)ny);
    y1[i] += 1e-4 * (1.0 + fabs(y[i]));
    if (ap_drv_rhs(t, y1, f1, s) != 0) return s->rhs_status ? s->rhs_status : AP_ERR_SOLVER;
    for (int j = 0; j < ny; j++) {
      double tol = 1e-10 * fmax(fabs(f0[j]), fabs(f1[j])) + 1e-13 * fmax_;
      if (fabs(f1[j] - f0[j]) > tol || !isfinite(f1[j])) dep[(size_t)i * ny + j] = 1;
    }
  }
  return AP_OK;
}

/* Shrink S (flags, n) until no member moves a component outside S. */
static void fixed_point(int n, int ny, const unsigned char *dep, int *S) {
  for (int changed = 1; changed;) {
    changed = 0;
    for (int i = 0; i < n; i++) {
      if (!S[i]) continue;
      for (int j = 0; j < ny; j++)
        if (dep[(size_t)i * ny + j] && (j >= n || !S[j])) {
          S[i] = 0, changed = 1;
          break;
        }
    }
  }
}

int ap_sim_free_coordinates(ap_sim *s, int *free_) {
  if (!s || !free_) return AP_ERR_ARG;
  if (s->dae) return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "ap_sim_free_coordinates: not in DAE "
                                 "mode (IDA controls every variable)");
  int n = s->n, ny = s->ny;
  if (ap_drv_event_defined(s)) {   /* an event may depend on any coordinate: none is free */
    for (int i = 0; i < n; i++) free_[i] = 0;
    return AP_OK;
  }
  unsigned char *dep = calloc((size_t)n * (size_t)ny + 1, 1);
  double *buf = malloc(sizeof(double) * (size_t)(4 * ny + 1));
  if (!dep || !buf) {
    free(dep), free(buf);
    return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  }
  double *f0 = buf, *f1 = buf + ny, *y1 = buf + 2 * ny, *y2 = buf + 3 * ny;
  memcpy(y2, s->y, sizeof(double) * (size_t)ny);
  for (int j = 0; j < ny; j++)   /* a second, less special state: no accidental zeros */
    y2[j] += 1e-3 * (1.0 + fabs(y2[j])) * (((j * 7919) % 13) / 6.0 - 1.0);
  int rc = dependencies(s, s->t, s->y, dep, f0, f1, y1);
  if (rc == AP_OK) rc = dependencies(s, s->t, y2, dep, f0, f1, y1);
  for (int i = 0; i < n; i++) free_[i] = 1;
  if (rc == AP_OK) fixed_point(n, ny, dep, free_);
  free(dep), free(buf);
  int ev = ap_drv_evaluate_current(s);   /* the data describes the current state again */
  if (rc != AP_OK) return ap_drv_fail(s, rc, "ap_sim_free_coordinates: %s", s->rhs_msg);
  return ev;
}

int ap_sim_set_uncontrolled(ap_sim *s, const int *flags) {
  if (!s) return AP_ERR_ARG;
  if (s->dae || !s->wt) return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "ap_sim_set_uncontrolled: "
                                           "not in DAE mode (IDA controls every variable)");
  for (int i = 0; i < s->n; i++) s->wt[i] = flags && flags[i] ? 0.0 : 1.0;
  return AP_OK;
}

int ap_sim_uncontrolled(const ap_sim *s, int i) {
  return s && s->wt && i >= 0 && i < s->n && s->wt[i] == 0.0;
}
