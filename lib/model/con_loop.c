/* Constraint kinds: the loop closures (coincident points, point on a line, point on a plane),
 * implicit holonomic constraints between two bodies (or a body and the ground):
 *
 *     phi = n . (xA - xB),   n a world axis (coincident) or fixed on body B (line, plane),
 *     phi' = n . (vA - vB) + (n x d) . wB,   d = xA - xB,
 *     gamma = -((alB x n + wB x (wB x n)) . d + 2 (wB x n) . (vA - vB) + n . (aA - aB)).
 *
 * Every row is an implicit holonomic row (projected after each step, a GGL row of the DAE
 * mode). A row's force is lambda n on body A and -lambda n on body B at the same world point.
 * Generic in the scalar (con_loop_cs.c); compile, names and forces are double build only. */
#include <stdio.h>
#include <string.h>

#include "model/builder.h"
#include "model/con_kind.h"

/* The world normal of loop row s and whether it turns with body2. */
static int loop_normal(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s, ap_sc *n) {
  const double *nb = c->dir;
  if (c->def.kind == AP_CON_COINCIDENT) {
    int axis = -1;
    for (int a = 0, seen = 0; a < 3; a++)
      if (c->def.axes & (1u << a) && seen++ == s) axis = a;
    n[0] = n[1] = n[2] = 0.0;
    n[axis] = 1.0;
    return 0;
  }
  if (c->def.kind == AP_CON_POINT_ON_LINE) nb = s == 0 ? c->n1 : c->n2;
  if (c->def.body2 < 0) {
    v3_copy_d(nb, n);
    return 0;
  }
  kbody B = ap_kin_body(M, S, c->def.body2);
  m3_mul_v_d(B.R, nb, n);
  return 1;
}

/* Row s of a loop: residual phi and the K1 coefficients of [v; 1] in row. */
static ap_sc loop_row(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s, ap_sc *row) {
  ap_sc *JA = S + M->off_tmp, *JB = JA + 3 * M->K1;
  ap_sc n[3], xA[3], xB[3], dd[3], nxd[3];
  int rot = loop_normal(M, S, c, s, n);
  ap_kin_point_d(M, S, c->def.body, c->def.point, xA, NULL, JA);
  ap_kin_point_d(M, S, c->def.body2, c->def.point2, xB, NULL, JB);
  for (int i = 0; i < 3; i++) dd[i] = xA[i] - xB[i];
  v3_cross(n, dd, nxd);
  const ap_sc *JwB = rot ? ap_kin_body(M, S, c->def.body2).Jw : NULL;
  for (int col = 0; col < M->K1; col++) {
    ap_sc r = 0.0;
    for (int i = 0; i < 3; i++) r += n[i] * (JA[i + 3 * col] - JB[i + 3 * col]);
    if (JwB) r += v3_dot(nxd, JwB + 3 * col);
    row[col] = r;
  }
  return v3_dot(n, dd);
}

static ap_sc loop_gamma(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s) {
  ap_sc n[3], xA[3], xB[3], rA[3], rB[3], vA[3], vB[3], aA[3], aB[3], dd[3], dv[3];
  int rot = loop_normal(M, S, c, s, n);
  ap_kin_point_d(M, S, c->def.body, c->def.point, xA, rA, NULL);
  ap_kin_point_d(M, S, c->def.body2, c->def.point2, xB, rB, NULL);
  ap_kin_point_motion(M, S, c->def.body, rA, vA, aA);
  ap_kin_point_motion(M, S, c->def.body2, rB, vB, aB);
  ap_sc g = 0.0;
  for (int i = 0; i < 3; i++) {
    dd[i] = xA[i] - xB[i], dv[i] = vA[i] - vB[i];
    g += n[i] * (aA[i] - aB[i]);
  }
  if (rot) {
    kbody B = ap_kin_body(M, S, c->def.body2);
    ap_sc wn[3], t1[3], t2[3];
    v3_cross(B.w, n, wn);
    v3_cross(B.al, n, t1);
    v3_cross(B.w, wn, t2);
    for (int i = 0; i < 3; i++) g += (t1[i] + t2[i]) * dd[i] + 2.0 * wn[i] * dv[i];
  }
  return -g;
}


static int loop_rows(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, ap_sc *S,
                     ap_sc *A, ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  ap_sc *row = S + M->off_tmp + 6 * (size_t)M->K1;
  (void)d, (void)t, (void)q;
  for (int r = 0; r < c->nrows; r++) {
    loop_row(M, S, c, r, row);
    ap_con_put_row(M, A, a0, c->row + r, NULL, row, 1, 0.0);
  }
  return AP_OK;
}

static int loop_gammas(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                       const ap_sc *v, ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  (void)d, (void)t, (void)q, (void)v;
  for (int r = 0; r < c->nrows; r++) gamma[c->row + r] = loop_gamma(M, S, c, r);
  return AP_OK;
}

const AP_SC(ap_con_eval) AP_SC(ap_con_loop_eval) = {NULL, loop_rows, loop_gammas, loop_row};

/* ---- double build: the kind tables -------------------------------------------------------- */
#ifndef AP_SC_COMPLEX
extern const struct ap_con_eval_cs ap_con_loop_eval_cs;

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

/* Unit normals n1, n2 of the unit direction t. */
static void normals_of(const double *t, double *n1, double *n2) {
  double e[3] = {0, 0, 0};
  int i = fabs(t[0]) <= fabs(t[1]) && fabs(t[0]) <= fabs(t[2]) ? 0
          : fabs(t[1]) <= fabs(t[2])                         ? 1
                                                              : 2;
  e[i] = 1.0;
  v3_cross(t, e, n1);
  double nn = v3_norm(n1);
  for (int k = 0; k < 3; k++) n1[k] /= nn;
  v3_cross(t, n1, n2);
}

static int compile_loop(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  (void)M;
  const ap_constraint_def *d = &c->def;
  int rc = ap_cc_body_ref(b, nm, "body", d->body, 0);
  if (rc == AP_OK) rc = ap_cc_body_ref(b, nm, "body2", d->body2, 1);
  if (rc != AP_OK) return rc;
  if (d->body == d->body2) FAIL("constraint '%s': body and body2 are the same body", nm);
  if (!ap_cc_finite(d->point, 3) || !ap_cc_finite(d->point2, 3))
    FAIL("constraint '%s': points not finite", nm);
  if (d->kind == AP_CON_COINCIDENT) {
    if ((d->axes & 7u) == 0 || (d->axes & ~7u))
      FAIL("constraint '%s': axes mask %u is not a set of world axes (bits 1 = x, 2 = y, "
           "4 = z)", nm, d->axes);
    c->nrows = (int)((d->axes & 1u) + ((d->axes >> 1) & 1u) + ((d->axes >> 2) & 1u));
    c->nhol = c->nrows;
    return AP_OK;
  }
  rc = ap_cc_unit_direction(b, nm, d->direction, c->dir);
  if (d->kind == AP_CON_POINT_ON_LINE) normals_of(c->dir, c->n1, c->n2);
  c->nrows = d->kind == AP_CON_POINT_ON_LINE ? 2 : 1;
  c->nhol = c->nrows;
  return rc;
}

static const char *loop_suffix(const ap_mcon *c, int r, char *buf) {
  static const char *const xyz[] = {".x", ".y", ".z"};
  (void)buf;
  if (c->def.kind == AP_CON_POINT_ON_LINE) return r ? ".n2" : ".n1";
  if (c->def.kind == AP_CON_POINT_ON_PLANE) return "";
  for (int a = 0, seen = 0; a < 3; a++)
    if (c->def.axes & (1u << a) && seen++ == r) return xyz[a];
  return "";
}

static int loop_wrench(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                       int root, const double *o, double *F, double *T) {
  int ina = ap_bm_in_subtree(M, c->def.body, root);
  int inb = c->def.body2 >= 0 && ap_bm_in_subtree(M, c->def.body2, root);
  if (ina == inb) return AP_OK;
  double x[3];   /* both act at A's point: B's force there carries the torque of (n x d) . wB */
  ap_kin_point(M, S, c->def.body, c->def.point, x, NULL, NULL);
  for (int r = 0; r < c->nrows; r++) {
    double n[3];
    loop_normal(M, S, c, r, n);
    for (int i = 0; i < 3; i++) n[i] *= ina ? lam[r] : -lam[r];
    ap_bm_add_force(n, x, o, F, T);
  }
  return AP_OK;
}

static int loop_tree_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                          size_t len) {
  (void)M;
  snprintf(why, len, "model '%s': constraint '%s' is a loop closure (rows on two bodies)",
           m->name, c->name);
  return -1;
}

#define LOOP_KIND(NAME)                                                                       \
  {NAME, compile_loop, loop_suffix, loop_wrench, loop_tree_body, NULL, NULL, 0,               \
   &ap_con_loop_eval, &ap_con_loop_eval_cs}
const ap_con_kind ap_con_coincident = LOOP_KIND("coincident");
const ap_con_kind ap_con_on_line = LOOP_KIND("point_on_line");
const ap_con_kind ap_con_on_plane = LOOP_KIND("point_on_plane");
#endif
