/* Scene checks at a time: every expression of a scene, and the equations of motion at the
 * initial state, so that what a run would refuse at t0 is refused before it starts, with the
 * location of the cause (`appell check` and `appell run` both go through
 * ap_scene_initial_state).
 *
 * sc_check_exprs evaluates every expression of t in the scene (joint drives, the ground's
 * omega and velocity, prescribed speeds, applied forces and torques, joint torques and forces,
 * motor set-points) at t with both time derivatives; of those not finite it reports the one
 * written first in the file, at its node (sc_expr_check). It only reads the scene: any
 * thread may call it (ap_scene_check_time). Expressions of the state are checked at the
 * initial state by sc_check_state_exprs (state.c).
 * sc_check_start runs the pipeline (ap_forward, orthonormal basis) at (t0, q0, v0); when that
 * gives a value that is not finite (other failures are left to the simulation, which reports
 * them as before) but works with every speed 0, the speeds overflow, and the message goes to
 * the largest number under initial: (heading_rate: 1e200). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

/* Is node a before node b in the file? */
static int before(const sc_node *a, const sc_node *b) {
  if (!a || !b) return a != NULL;
  return a->line < b->line || (a->line == b->line && a->col < b->col);
}

static void consider(const sc_expr *e, double t, const sc_expr **first) {
  double f[3];
  if (!e->timed || sc_prog_nvars(e->prog) > 0 || sc_expr_eval(e, t, f) == 0) return;
  if (!*first || before(e->node, (*first)->node)) *first = e;
}

static void consider_ground(const sc_ground *g, double t, const sc_expr **first) {
  consider(&g->omega, t, first);
  consider(&g->vel[0], t, first);
  consider(&g->vel[1], t, first);
}

int sc_check_exprs(sc_ctx *c, const sc_scene *s, double t) {
  const sc_expr *first = NULL;
  consider_ground(&s->ground, t, &first);
  for (int j = 0; j < s->nj; j++)
    for (int i = 0; i < 3; i++) consider(&s->joints[j].drive[i], t, &first);
  for (int k = 0; k < s->nc; k++) {
    consider(&s->cons[k].value, t, &first);
    consider_ground(&s->cons[k].ground, t, &first);
  }
  for (int e = 0; e < s->ne; e++)
    for (int i = 0; i < 3; i++) {
      consider(&s->effs[e].force[i], t, &first);
      consider(&s->effs[e].torque[i], t, &first);
    }
  for (int e = 0; e < s->ne; e++) consider(&s->effs[e].value, t, &first);   /* joint effects */
  return first ? sc_expr_check(c, first, t) : AP_OK;
}

/* ---- the equations of motion at the initial state ------------------------------------------ */

static int forward_at(const ap_model *m, ap_data *d, double t, const double *q, const double *v) {
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)d->n);
  memcpy(d->v, v, sizeof(double) * (size_t)d->k);
  d->basis = AP_BASIS_ORTHONORMAL;
  d->speeds_from_e = 0;
  int rc = ap_forward(m, d);
  for (int i = 0; rc == AP_OK && i < d->k; i++)
    if (!isfinite(d->vdot[i])) {
      snprintf(d->msg, sizeof d->msg, "the acceleration of speed %d is %g", i, d->vdot[i]);
      rc = AP_ERR_NAN;
    }
  return rc;
}

/* The scalar under n with the largest magnitude (*big), or NULL. */
static const sc_node *largest(const sc_node *n, double *big) {
  if (n->kind == SC_SCALAR) {
    sc_ctx scratch = {"", "", AP_OK};
    double x = 0.0;
    if (sc_number(&scratch, n, &x) != AP_OK || !(fabs(x) > *big)) return NULL;
    *big = fabs(x);
    return n;
  }
  const sc_node *best = NULL;
  for (int i = 0; i < n->n; i++) {
    const sc_node *b = largest(n->kids[i], big);
    if (b) best = b;
  }
  return best;
}

int sc_check_start(sc_ctx *c, const sc_scene *s, const ap_model *m, const double *q0,
                   const double *v0) {
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) {
    sc_err(c, s->root, "out of memory");
    return c->status = AP_ERR_NOMEM;
  }
  int rc = forward_at(m, d, s->run.t0, q0, v0);
  if (rc != AP_ERR_NAN && rc != AP_ERR_CALLBACK) return ap_data_free(d), AP_OK;   /* not ours */
  char why[sizeof d->msg], hint[96] = "";
  memcpy(why, d->msg, sizeof why);
  const sc_node *init = sc_map_get(s->root, "initial"), *at = init ? init : s->root;
  memset(d->v, 0, sizeof(double) * (size_t)d->k);
  double big = 0.0;
  if (init && forward_at(m, d, s->run.t0, q0, d->v) == AP_OK) {
    const sc_node *n = largest(init, &big);
    if (n) at = n, snprintf(hint, sizeof hint, "; with every speed 0 they are: is %g too large?",
                            big);
  }
  ap_data_free(d);
  return sc_err(c, at, "the equations of motion cannot be evaluated at the initial state (t = "
                "%g): %s%s", s->run.t0, why, hint);
}
