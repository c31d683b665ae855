/* The body model's evaluator hooks between steps (core/core.h) and the public queries of
 * body.h (double build only; the per-evaluation hooks are in hooks.c).
 *
 * project_q (after each accepted step): quaternions back to unit norm when they drifted by more
 * than AP_QUAT_TOL, then loop closures and wheel contacts phi(q, t) = 0 (the implicit
 * holonomic rows) by Gauss-Newton with minimum-norm steps dv (lstsq on their Jacobian) mapped
 * to q through N. Corrections below the tolerances are
 * not applied, so the stepper restarts only when something really moved.
 * Everything writes into the data's scratch; the model is never modified.
 * Counters: energy per ap_body_energy. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linalg/linalg.h"
#include "model/con_friction.h"
#include "model/con_kind.h"
#include "model/tree_model.h"   /* the tree path's layout and queries (m->ops) */

/* ---- hooks ------------------------------------------------------------------------------- */

/* The complex-step build evaluates the model unless a user callback (a C function of doubles)
 * takes part. */
int ap_bm_cs_blocker(const ap_model *m, char *msg, size_t len) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++)
    if (M->cons[ci].plane == 3) {
      snprintf(msg, len, "constraint '%s' rolls on a height field (z = h(x, y), a C function of "
               "doubles)", M->cons[ci].name);
      return -1;
    } else if (M->cons[ci].kind->no_cs) {
      snprintf(msg, len, "constraint '%s' is %s", M->cons[ci].name, M->cons[ci].kind->no_cs);
      return -1;
    }
  for (int i = 0; i < M->ne; i++)
    if (M->effs[i].def.kind == AP_EFFECT_USER) {
      snprintf(msg, len, "effect '%s' is a user effect (a C callback of doubles)",
               M->effs[i].name);
      return -1;
    }
  return 0;
}

void ap_bm_destroy(void *impl) {
  ap_bmodel *M = impl;
  if (!M) return;
  if (M->fast && M->fast->destroy) M->fast->destroy(M->fast);
  for (int b = 0; b < M->nb && M->bodies; b++) free(M->bodies[b].cols);
  free(M->bodies);
  free(M->joints);
  free(M->joint_topo);
  free(M->cons);
  free(M->effs);
  free(M);
}

/* ---- projection of q ---------------------------------------------------------------------- */

static int normalize_quats(const ap_model *m, ap_data *d, double *q, double *change) {
  const ap_bmodel *M = ap_bm(m);
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    if (J->quat < 0) continue;
    double *p = q + J->qidx[J->quat];
    double nn = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
    if (!(nn > 1e-6) || !isfinite(nn)) {
      AP_BM_MSG(d, "model '%s': joint '%s': its quaternion has norm %g at t = %.17g", m->name,
                J->name, nn, d->t);
      return AP_ERR_NAN;
    }
    if (fabs(nn - 1.0) <= AP_QUAT_TOL) continue;
    for (int i = 0; i < 4; i++) p[i] /= nn;
    *change += fabs(nn - 1.0);
  }
  return AP_OK;
}

/* q += N(q) dv, quaternions re-normalized (model.h). */
void ap_bm_step_q(const ap_bmodel *M, double *q, const double *dv) {
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    for (int i = 0; i < J->ndrivable; i++)
      if (J->qidx[i] >= 0) q[J->qidx[i]] += dv[J->vidx[i]];
    if (J->quat < 0) continue;
    double *p = q + J->qidx[J->quat], N[12], dq[4] = {0, 0, 0, 0};
    const double *w = dv + J->vidx[J->wofs];
    ap_quat_N(p, N, 4, 0, 0);
    for (int r = 0; r < 4; r++)
      for (int c = 0; c < 3; c++) dq[r] += N[r + 4 * c] * w[c];
    double nn = 0.0;
    for (int r = 0; r < 4; r++) p[r] += dq[r], nn += p[r] * p[r];
    nn = sqrt(nn);
    for (int r = 0; r < 4; r++) p[r] /= nn;
  }
}

static double max_abs(const double *x, int n) {
  double mx = 0.0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

/* The constraint row of the largest |phi| among the implicit holonomic rows. */
static int hol_row(const ap_bmodel *M, const double *phi) {
  int worst = 0, s = 0;
  for (int i = 1; i < M->nloop; i++)
    if (fabs(phi[i]) > fabs(phi[worst])) worst = i;
  for (int ci = 0; ci < M->nc; ci++)
    for (int r = 0; r < M->cons[ci].nhol; r++, s++)
      if (s == worst) return M->cons[ci].row + M->cons[ci].hrow + r;
  return 0;
}

static int close_loops(const ap_model *m, ap_data *d, double *q, double *S, double *change) {
  if (m->ops_impl && !m->ops) return ap_tree_close_rows(m->ops_impl, d, q, change);   /* shadow */
  const ap_bmodel *M = ap_bm(m);
  int k = M->k, nl = M->nloop;
  double *P = S + M->off_proj, *JlT = P, *phi = JlT + (size_t)nl * k, *rhs = phi + nl;
  double *dv = rhs + nl, *work = dv + k;
  int *iwork = (int *)(work + M->proj_work);
  double tol = AP_LOOP_TOL * M->lscale, err = 0.0, resid = 0.0;
  for (int it = 0; it <= AP_LOOP_ITER; it++) {
    int rc = ap_kin_position(m, d, d->t, q, S);
    if (rc != AP_OK) return rc;
    ap_con_loops(M, S, phi, JlT);
    err = max_abs(phi, nl);
    if (err <= tol) return AP_OK;
    if (it == AP_LOOP_ITER) break;
    for (int s = 0; s < nl; s++) rhs[s] = -phi[s];
    rc = ap_la_lstsq_At(k, nl, JlT, rhs, 1e-10, dv, &resid, work, iwork);
    if (rc != AP_OK) break;
    ap_bm_step_q(M, q, dv);
    for (int c = 0; c < k; c++) *change += fabs(dv[c]);
  }
  AP_BM_MSG(d, "model '%s': the loop closures and wheel contacts cannot be closed at "
            "t = %.17g: row '%s' is off by %.3g m after %d Gauss-Newton steps (tolerance %.3g m)",
            m->name, d->t, m->constraint_names[hol_row(M, phi)], err, AP_LOOP_ITER, tol);
  return AP_ERR_INCONSISTENT;
}

/* A disk or torus cannot go through lying flat. Trial stages inside the singular band
 * (|u_p| < flat_tol) are refused by the position stage as recoverable, so the stepper creeps
 * towards the band with ever smaller steps; an accepted state within 2 flat_tol therefore
 * means the motion itself reached lying flat, and it stops here with a clear error. A step
 * could also jump over the band: the contact point would then jump to the far side of the rim
 * (the support function has a kink there). The direction from the centre to the contact point,
 * in world axes, c = -(e_z - a_z a) / |e_z - a_z a| (a = R e_z the axis), turns continuously
 * along any motion that stays off the band: it does not depend on the spin about the axis (a
 * wheel on a revolute joint may turn through more than 90 degrees in one accurate step: its
 * angle grows linearly), and near upright it stays close to -e_z whatever the heading. So a
 * turn of c beyond 90 degrees between accepted steps means the step crossed the kink. (The
 * contact point's position on the rim, in body axes, runs round at the spin rate: it cannot
 * tell a fast wheel from a flip.) */
#define FLAT_HINT                                                                          \
  "; to stop the run at the fall, add `collide: stop` to the body that touches the ground " \
  "first (docs/scenes.md, Events)"

/* via: the name of what holds the body on the ground, a plane-contact joint or a wheel-contact
 * constraint (a joint when B's own joint has that name). The tilt from upright is 90 degrees
 * minus the axis's angle from the vertical, asin(n). */
static int flat_error(const ap_model *m, ap_data *d, const ap_mbody *B, const char *name,
                      double n, double turn, double t_prev) {
  const char *what = B->shape.kind == AP_SHAPE_DISK ? "disk" : "torus";
  double from_vertical = asin(fmin(n, 1.0)) * 57.29577951308232;
  char via[160];
  const ap_bmodel *M = ap_bm(m);
  int joint = 0;
  for (int j = 0; j < M->nj; j++)
    joint |= M->joints[j].kind == AP_JOINT_PLANE_CONTACT && &M->bodies[M->joints[j].child] == B &&
             strcmp(M->joints[j].name, name) == 0;
  snprintf(via, sizeof via, joint ? "joint '%s' (plane contact)" : "constraint '%s'", name);
  if (turn > 0)
    AP_BM_MSG(d, "model '%s': body '%s', %s: the %s passed through lying flat between t = "
              "%.17g and t = %.17g (its contact point turned by %.0f degrees about the centre "
              "in one step; tilted %.6g degrees from upright now): a falling %s lands on its "
              "face, which one contact point does not describe" FLAT_HINT, m->name, B->name,
              via, what, t_prev, d->t, turn, 90.0 - from_vertical, what);
  else
    AP_BM_MSG(d, "model '%s': body '%s', %s: the %s reached lying flat at t = %.17g, tilted "
              "%.6g degrees from upright (axis %.3g degrees from the vertical, within 2 flat_tol "
              "= %.3g): its contact point is undefined (a falling %s lands on its face)"
              FLAT_HINT, m->name, B->name, via, what, d->t, 90.0 - from_vertical, from_vertical,
              2 * B->shape.flat_tol, what);
  return AP_ERR_SINGULAR;
}

/* One disk or torus with rotation R (body to world, column-major) and tracking block trk:
 * c (3), whether it is set (1), its time (1). */
static int track_one(const ap_model *m, ap_data *d, const ap_mbody *B, const char *via,
                     const double *R, double *trk, int track) {   /* via: flat_error's name */
  const double *a = R + 6;                   /* the axis in world axes, R e_z */
  double n = hypot(a[0], a[1]);              /* = |e_z - a_z a| = |u_perp| */
  if (track && n < 2 * B->shape.flat_tol) return flat_error(m, d, B, via, n, 0.0, 0.0);
  if (!(n > 0)) return AP_OK;   /* exactly flat while assembling: the position stage reports it */
  double c[3] = {a[2] * a[0] / n, a[2] * a[1] / n, -n};
  double cos_turn = c[0] * trk[0] + c[1] * trk[1] + c[2] * trk[2];
  if (track && trk[3] != 0.0 && cos_turn < 0.0)
    return flat_error(m, d, B, via, n, acos(fmax(-1.0, cos_turn)) * 57.29577951308232, trk[4]);
  trk[0] = c[0], trk[1] = c[1], trk[2] = c[2], trk[3] = track ? 1.0 : 0.0, trk[4] = d->t;
  return AP_OK;
}

static int is_wheel_shape(const ap_mbody *B) {
  return B->shape.kind == AP_SHAPE_DISK || B->shape.kind == AP_SHAPE_TORUS;
}

/* Plane-contact disks and tori from q; wheel contacts from the kinematics at q, computed here
 * unless `fresh` says the scratch holds them already. */
static int track_flat(const ap_model *m, ap_data *d, const double *q, double *S, int track,
                      int fresh) {
  const ap_bmodel *M = ap_bm(m);
  int rc = AP_OK;
  for (int j = 0; j < M->nj && rc == AP_OK; j++) {
    const ap_mjoint *J = &M->joints[j];
    const ap_mbody *B = &M->bodies[J->child];
    if (J->kind != AP_JOINT_PLANE_CONTACT || !is_wheel_shape(B)) continue;
    double R[9];
    ap_quat_normalized_matrix(q + J->qidx[J->quat], R);
    rc = track_one(m, d, B, J->name, R, ap_kin_joint(M, S, j).track, track);
  }
  if (rc != AP_OK || !M->nwheel) return rc;
  if (!fresh) rc = ap_kin_position(m, d, d->t, q, S);
  for (int ci = 0; ci < M->nc && rc == AP_OK; ci++) {
    const ap_mcon *c = &M->cons[ci];
    const ap_mbody *B = c->wheel >= 0 ? &M->bodies[c->def.body] : NULL;
    if (!B || !is_wheel_shape(B)) continue;
    rc = track_one(m, d, B, c->name, ap_kin_body(M, S, c->def.body).R,
                   ap_contact_geom(M, S, c).track, track);
  }
  return rc;
}

int ap_bm_project(const ap_model *m, ap_data *d, double *q, double *S, double *change,
                  int track) {
  const ap_bmodel *M = ap_bm(m);
  *change = 0.0;
  int rc = M->nquat ? normalize_quats(m, d, q, change) : AP_OK;
  if (rc == AP_OK && M->nloop) rc = close_loops(m, d, q, S, change);
  if (rc == AP_OK && (M->nquat || M->nwheel)) rc = track_flat(m, d, q, S, track, M->nloop > 0);
  return rc;
}

int ap_bm_project_q(const ap_model *m, ap_data *d, double *q, double *S, double *change) {
  return ap_bm_project(m, d, q, S, change, 1);
}

int ap_bm_check_q(const ap_model *m, ap_data *d, const double *q, double *S) {
  const ap_bmodel *M = ap_bm(m);
  return M->nquat || M->nwheel ? track_flat(m, d, q, S, 1, 0) : AP_OK;
}

/* ---- public queries ------------------------------------------------------------------------ */

int ap_model_is_body_model(const ap_model *m) {
  return m && m->ev.position == ap_bm_position;
}

int ap_model_body_count(const ap_model *m) {
  return ap_model_is_body_model(m) ? ap_bm(m)->nb : AP_ERR_ARG;
}

int ap_model_find_body(const ap_model *m, const char *name) {
  if (!ap_model_is_body_model(m) || !name) return -1;
  const ap_bmodel *M = ap_bm(m);
  for (int b = 0; b < M->nb; b++)
    if (strcmp(M->bodies[b].name, name) == 0) return b;
  return -1;
}

static int find_name(char **names, int count, const char *name) {
  for (int i = 0; name && i < count; i++)
    if (strcmp(names[i], name) == 0) return i;
  return -1;
}

int ap_model_find_coord(const ap_model *m, const char *name) {
  return m ? find_name(m->coord_names, m->n, name) : -1;
}

int ap_model_find_speed(const ap_model *m, const char *name) {
  return m ? find_name(m->speed_names, m->k, name) : -1;
}

static const ap_mjoint *joint_by_id(const ap_model *m, int joint) {
  if (!ap_model_is_body_model(m)) return NULL;
  const ap_bmodel *M = ap_bm(m);
  return joint >= 0 && joint < M->nj ? &M->joints[M->joint_topo[joint]] : NULL;
}

int ap_joint_coord_index(const ap_model *m, int joint) {
  const ap_mjoint *j = joint_by_id(m, joint);
  if (!j) return AP_ERR_ARG;
  for (int i = 0; i < j->nq; i++)
    if (j->qidx[i] >= 0) return j->qidx[i];
  return -1;
}

int ap_joint_speed_index(const ap_model *m, int joint) {
  const ap_mjoint *j = joint_by_id(m, joint);
  if (!j) return AP_ERR_ARG;
  for (int i = 0; i < j->nv; i++)
    if (j->vidx[i] >= 0) return j->vidx[i];
  return -1;
}

int ap_constraint_row_index(const ap_model *m, int constraint) {
  if (!ap_model_is_body_model(m)) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(m);
  return constraint >= 0 && constraint < M->nc ? M->cons[constraint].row : AP_ERR_ARG;
}

int ap_body_eval(const ap_model *m, ap_data *d) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d)) return AP_ERR_ARG;
  if (m->ops) return ap_tree_body_eval(m, d, ap_tree_ws_of(d));
  double *S = ap_bm_scratch(d);
  int rc = ap_kin_position(m, d, d->t, d->q, S);
  if (rc == AP_OK) ap_kin_velocity(ap_bm(m), d->v, S);
  return rc;
}

int ap_body_get_state(const ap_model *m, const ap_data *d, int body, ap_body_state *out) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !out || body < 0 ||
      body >= ap_bm(m)->nb)
    return AP_ERR_ARG;
  const ap_bmodel *M = ap_tree_layout(m);
  double *S = ap_bm_scratch(d);
  kbody C = ap_kin_body(M, S, body);
  memset(out, 0, sizeof *out);
  v3_copy(C.o, out->pos);
  memcpy(out->R, C.R, sizeof out->R);
  for (int i = 0; i < 3; i++) out->com[i] = C.o[i] + C.rcom[i];
  v3_copy(C.w, out->omega);
  v3_copy(C.vo, out->vel);
  v3_cross_add(C.w, C.rcom, out->vel);
  const ap_mjoint *j = &M->joints[M->bodies[body].joint];
  const double *rc = NULL;
  if (j->kind == AP_JOINT_PLANE_CONTACT) rc = ap_kin_joint(M, S, M->bodies[body].joint).rc;
  for (int ci = 0; ci < M->nc && !rc; ci++)
    if (M->cons[ci].wheel >= 0 && M->cons[ci].def.body == body)
      rc = ap_contact_geom(M, S, &M->cons[ci]).rc;
  out->has_contact = rc != NULL;
  for (int i = 0; i < 3 && rc; i++) out->contact[i] = C.o[i] + rc[i];
  return AP_OK;
}

int ap_body_point_jacobian(const ap_model *m, const ap_data *d, int body, const double p[3],
                           double *Jw, double *Jv, double rw[3], double rv[3], double aw[3],
                           double av[3]) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !p || body < 0 ||
      body >= ap_bm(m)->nb)
    return AP_ERR_ARG;
  if (m->ops) return AP_ERR_UNSUPPORTED;   /* the tree path keeps no Jacobian columns */
  const ap_bmodel *M = ap_bm(m);
  double *S = ap_bm_scratch(d), *JP = S + M->off_tmp, r[3];
  kbody C = ap_kin_body(M, S, body);
  size_t k = (size_t)M->k;
  ap_kin_point(M, S, body, p, NULL, r, JP);
  if (Jw) memcpy(Jw, C.Jw, 3 * k * sizeof *Jw);
  if (Jv) memcpy(Jv, JP, 3 * k * sizeof *Jv);
  if (rw) v3_copy(C.Jw + 3 * k, rw);
  if (rv) v3_copy(JP + 3 * k, rv);
  if (aw) v3_copy(C.al, aw);
  if (av) ap_kin_point_motion(M, S, body, r, NULL, av);
  return AP_OK;
}

int ap_body_energy(const ap_model *m, ap_data *d, double *kinetic, double *potential) {
  if (ap_model_is_body_model(m) && d) d->cnt.energy++;
  int rc = ap_body_eval(m, d);
  if (rc != AP_OK) return rc;
  const ap_bmodel *M = ap_tree_layout(m);
  double *S = ap_bm_scratch(d), T = 0.0;
  for (int b = 0; b < M->nb; b++) {
    kbody C = ap_kin_body(M, S, b);
    double vc[3], Iw[3];
    v3_copy(C.vo, vc);
    v3_cross_add(C.w, C.rcom, vc);
    m3_mul_v(C.Iw, C.w, Iw);
    T += 0.5 * M->bodies[b].mass * v3_dot(vc, vc) + 0.5 * v3_dot(C.w, Iw);
  }
  if (kinetic) *kinetic = T;
  if (potential) *potential = ap_eff_potential(M, S);
  return AP_OK;
}

long ap_body_effect_count(const ap_model *m, const ap_data *d, int effect) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || effect < 0 ||
      effect >= ap_bm(m)->ne)
    return -1;
  return (long)ap_bm_scratch(d)[ap_tree_layout(m)->off_cnt + (size_t)effect];
}

int ap_body_project_q(const ap_model *m, ap_data *d, double *q, double *change) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !q) return AP_ERR_ARG;
  double ch = 0.0;
  int rc = ap_bm_project(m->ops ? &ap_tree_plan(m)->sm : m, d, q, ap_bm_scratch(d), &ch, 0);
  if (change) *change = ch;
  return rc;
}

int ap_body_loop_residual(const ap_model *m, ap_data *d, double *phi_max) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !phi_max) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(m);
  *phi_max = 0.0;
  if (!M->nloop) return AP_OK;
  if (m->ops) return ap_tree_hol_residual(ap_tree_plan(m), d, d->q, phi_max);
  double *S = ap_bm_scratch(d), *JlT = S + M->off_proj, *phi = JlT + (size_t)M->nloop * M->k;
  int rc = ap_kin_position(m, d, d->t, d->q, S);
  if (rc != AP_OK) return rc;
  ap_con_loops(M, S, phi, JlT);
  *phi_max = max_abs(phi, M->nloop);
  return AP_OK;
}

/* Minimum-norm free speeds: A_f x = -(a0 + A_g v_g) by lstsq on A_f^T, A (b x k) and a0 of
 * the position stage at q (the data's on the dense path). */
static int min_norm_speeds(const ap_model *m, ap_data *d, const double *A, const double *a0,
                           const int *given, double *v) {
  int k = m->k, b = m->b, nf = 0;
  for (int c = 0; c < k; c++) nf += !given[c];
  size_t lw = ap_la_work_size(nf, b), liw = ap_la_iwork_size(nf, b);
  double *AfT = calloc((size_t)nf * b + b + nf + lw + 1, sizeof *AfT);
  int *iw = calloc(liw + 1, sizeof *iw);
  if (!AfT || !iw) {
    free(AfT), free(iw);
    AP_BM_MSG(d, "model '%s': out of memory completing the speeds", m->name);
    return AP_ERR_NOMEM;
  }
  /* scale: the largest term of the rows and their floor, one model length scale (or radian)
   * per second on every speed (core/core.h), so that the check follows the model's units */
  double *rhs = AfT + (size_t)nf * b, *x = rhs + b, *work = x + nf, resid = 0.0, scale = 0.0;
  for (int s = 0; s < b; s++) {
    rhs[s] = -a0[s];
    for (int c = 0, f = 0; c < k; c++) {
      double a = A[s + (size_t)c * b];
      double sc = m->vscale ? m->vscale[c] : 1.0;
      scale = fmax(scale, fabs(a * v[c]) + AP_ROW_FLOOR_PER_S * fabs(a) * sc);
      if (given[c]) rhs[s] -= a * v[c];
      else AfT[f++ + (size_t)s * nf] = a;
    }
  }
  int rc = nf ? ap_la_lstsq_At(nf, b, AfT, rhs, 1e-12, x, &resid, work, iw) : AP_OK;
  for (int c = 0, f = 0; rc == AP_OK && c < k; c++)
    if (!given[c]) v[c] = x[f++];
  double res = rc == AP_OK ? ap_constraint_residual(d, v) : 0.0;
  free(AfT), free(iw);
  if (rc != AP_OK) return rc;
  if (res > 1e-9 * fmax(scale, max_abs(a0, b))) {
    AP_BM_MSG(d, "model '%s': the given speeds leave the constraints violated by %.3g",
              m->name, res);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}

/* The tree path: its own completion (the free speeds of its partition 0) runs the position
 * stage; then the minimum-norm completion as on the dense path, with A's columns from the
 * tree's rows (A e_c), so that both paths start a scene from the same speeds (a sleigh on a
 * turntable started with (-0.2454, 0, 0) instead of (-0.1745, 0.1067, -0.0315): found by
 * tests/difftest, docs/testing.md). */
static int tree_complete_speeds(const ap_model *m, ap_data *d, const int *given, double *v) {
  ap_tree_ws *ws = ap_tree_ws_of(d);
  int k = m->k, b = m->b;
  if (ws->P->comp) {   /* the same least squares, tree by tree */
    int rc = ap_tree_position(m, d, ws, 1);
    return rc == AP_OK ? ap_tree_complete_min_norm(m, d, ws, given, v) : rc;
  }
  double *A = calloc((size_t)b * k + 2 * (size_t)k, sizeof *A);
  if (!A) {
    AP_BM_MSG(d, "model '%s': out of memory completing the speeds", m->name);
    return AP_ERR_NOMEM;
  }
  double *unit = A + (size_t)b * k, *v_in = unit + k;
  memcpy(v_in, v, (size_t)k * sizeof *v);
  /* its partition may not avoid every given speed: then the least squares below decides */
  int rc = ap_tree_complete_speeds(m, d, ws, given, v);
  if ((rc != AP_OK && rc != AP_ERR_INCONSISTENT) || b == 0) {
    free(A);
    return rc;
  }
  for (int c = 0; c < k; c++) {
    if (given[c]) v[c] = v_in[c];   /* as given, not as the tree's solve returned them */
    unit[c] = 1.0;
    ap_tree_amul(ws, d, unit, 0, A + (size_t)c * b, NULL);
    unit[c] = 0.0;
  }
  rc = min_norm_speeds(m, d, A, d->a0, given, v);
  free(A);
  return rc;
}

int ap_body_complete_speeds(const ap_model *m, ap_data *d, const double *q, const int *given,
                            double *v) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !q || !given || !v)
    return AP_ERR_ARG;
  int k = m->k, b = m->b;
  memcpy(d->q, q, (size_t)m->n * sizeof *q);
  if (m->ops) return tree_complete_speeds(m, d, given, v);
  memset(d->g, 0, (size_t)k * k * sizeof *d->g);
  memset(d->A, 0, (size_t)(b ? b : 1) * k * sizeof *d->A);
  memset(d->a0, 0, (size_t)(b ? b : 1) * sizeof *d->a0);
  int rc = ap_bm_position(m, d, ap_bm_scratch(d));
  if (rc != AP_OK || b == 0) return rc;
  return min_norm_speeds(m, d, d->A, d->a0, given, v);
}
