/* When CVODE BDF's Newton matrix is stale: vectors whose inverse length scales part of the
 * right-hand side's Jacobian, watched between steps (stepper.h, ap_step_jacobian_watch).
 *
 * A sliding contact's friction acts along s / |s|, s its slip velocity, whose derivative
 * (I - s^ s^T) / |s| grows without bound as |s| -> 0. CVODE keeps the Jacobian it made for up
 * to 51 steps (20 between Newton matrices) unless its Newton iteration fails. Made at a slip
 * onset (|s| = 0 or round-off) the Jacobian is far stiffer than the one a few steps later:
 * I - gamma J then damps every Newton correction, the iteration stalls after one small
 * correction, CVODE's convergence test (rate 1 until measured) passes it, and the step keeps
 * its predictor with an error estimate of about 0 (difftest seed 136: 0.81 off at rtol 1e-8,
 * docs/steppers.md). So the Jacobian is made again before the next step whenever a watched
 * vector w_i has moved by more than JW_THETA times the shorter of |w_i| and its value where
 * the Jacobian was made (the Jacobian's 1/|s| part changed by about that fraction); after
 * ap_step_reset the state where it was made is unknown, and the next accepted step forces one. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "integrate/stepper.h"

#define JW_THETA 0.5

struct ap_step_jwatch {
  int m;             /* watched vectors (2 numbers each) */
  int prev_ok;       /* prev holds the values at the last accepted state */
  int jac_ok;        /* jac holds the values where the Jacobian was made */
  int made;          /* the last step made the Jacobian (at its start: prev) */
  int force;         /* make it before the next step */
  double rho;        /* relative increment of the difference quotients (stepper_cvjac.c); 0:
                        CVODE's own */
  double *prev, *jac;
};

void ap_step_jw_free(ap_stepper *s) {
  if (!s->jw) return;
  free(s->jw->prev);
  free(s->jw);
  s->jw = NULL;
}

static int jw_size(ap_stepper *s, int m) {
  if (s->jw && s->jw->m == m) return AP_OK;
  ap_step_jw_free(s);
  s->jw = calloc(1, sizeof *s->jw);
  if (s->jw) s->jw->prev = malloc(sizeof(double) * 4 * (size_t)(m > 0 ? m : 1));
  if (!s->jw || !s->jw->prev) return ap_step_jw_free(s), AP_ERR_NOMEM;
  s->jw->jac = s->jw->prev + 2 * m, s->jw->m = m;
  return AP_OK;
}

/* 1 when w (2 numbers) moved by more than JW_THETA of the shorter length since j. */
static int moved(const double *w, const double *j) {
  double d = hypot(w[0] - j[0], w[1] - j[1]);
  return d > JW_THETA * fmin(hypot(w[0], w[1]), hypot(j[0], j[1]));
}

int ap_step_jacobian_watch(ap_stepper *s, int m, const double *w) {
  if (!s || m < 0 || (m && !w)) return AP_ERR_ARG;
  if (!ap_step_native_projection(s->meth)) return AP_OK;   /* no Newton matrix (CVODE BDF) */
  if (jw_size(s, m) != AP_OK) return AP_ERR_NOMEM;
  struct ap_step_jwatch *jw = s->jw;
  if (jw->made) {
    memcpy(jw->jac, jw->prev, sizeof(double) * 2 * (size_t)m);
    jw->jac_ok = jw->prev_ok, jw->made = 0;
  }
  int stale = !jw->jac_ok;
  for (int i = 0; i < m && !stale; i++) stale = moved(w + 2 * i, jw->jac + 2 * i);
  if (stale) {   /* made at the start of the next step, i.e. here */
    jw->force = 1, jw->jac_ok = 1;
    memcpy(jw->jac, w, sizeof(double) * 2 * (size_t)m);
  }
  memcpy(jw->prev, w, sizeof(double) * 2 * (size_t)m);
  jw->prev_ok = 1;
  return AP_OK;
}

int ap_step_jw_force(const ap_stepper *s) { return s->jw && s->jw->force; }

void ap_step_jw_stepped(ap_stepper *s, int made) {
  if (!s->jw) return;
  s->jw->made |= made;
  s->jw->force = 0;
}

int ap_step_jacobian_increment(ap_stepper *s, double rho) {
  if (!s || !(rho >= 0)) return AP_ERR_ARG;
  if (!ap_step_native_projection(s->meth)) return AP_OK;
  if (jw_size(s, s->jw ? s->jw->m : 0) != AP_OK) return AP_ERR_NOMEM;
  s->jw->rho = rho;
  return AP_OK;
}

double ap_step_jw_rho(const ap_stepper *s) { return s->jw ? s->jw->rho : 0.0; }

void ap_step_jw_reset(ap_stepper *s) {
  if (s->jw) s->jw->prev_ok = 0, s->jw->made = 1;
}
