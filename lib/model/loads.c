/* Wheel loads: the normal force of every wheel contact (a rolling or wheel knife-edge
 * constraint on a body that is not on a plane-contact joint), whatever form the vehicle is
 * written in (docs/vehicles.md "Wheel loads"). Double build only.
 *
 * The wheels under one chassis (the ancestor joined to the ground) share what holds the chassis
 * up. Newton-Euler for the chassis' subtree T about the centroid c of the contact points p_i:
 *
 *     R_F = sum_T m a_com - F_eff(T) - F_con(T)
 *     R_M = sum_T [(x_com - c) x m a_com + Iw al + w x Iw w] - M_eff(T) - M_con(T)
 *
 * with al = Jw v' + the bias, and F_con, M_con the forces of every constraint row except the
 * wheels' contact rows .z. R is what the normal loads N_i e_z must supply: on a free chassis
 * the contact rows do it (R = sum lambda_z,i e_z at p_i); on a planar chassis the rows .z are
 * identically satisfied (multipliers zero) and R is the joint's vertical reaction and its roll
 * and pitch moments, which in reality the wheels carry. With offsets (a_i, b_i) = p_i - c:
 *
 *     sum N_i = R_F,z,   sum b_i N_i = R_M,x,   -sum a_i N_i = R_M,y,
 *
 * whose minimum-norm solution is N_i = R_F,z / n + (a_i, b_i) . S^+ (-R_M,y, R_M,x), with
 * S = sum (a_i, b_i) (a_i, b_i)^T (sum a_i = sum b_i = 0 about the centroid). The rank r of S
 * (2 for three or more non-collinear contacts, 1 collinear) tells: n = r + 1 unique; n > r + 1
 * statically indeterminate (the minimum-norm distribution, AP_LOAD_MIN_NORM); under a planar
 * joint with r < 2 the joint keeps the tilting moment about the contacts' line
 * (AP_LOAD_JOINT). Both forms of a vehicle give the same numbers.
 *
 * A planar chassis may also hold up wheels that are not in its subtree: bodies on their own
 * plane-contact joints joined to it by loop constraints (diff_drive_loops.yaml: each wheel's
 * centre held at its hub, a point of its axis on the axle line). The group is then the
 * chassis' subtree and those wheels' subtrees: its Newton-Euler (loop forces between its
 * members cancel) gives what the joint's reaction and the plane-contact normal forces supply
 * together, and it is shared among all the group's contacts as above (a plane-contact wheel's
 * own normal force is part of it, not added). */
#include <stdlib.h>
#include <string.h>

#include "model/con_kind.h"
#include "model/tree_model.h"

/* The body joined to the ground above body b. */
static int chassis_of(const ap_bmodel *M, int b) {
  for (;;) {
    int p = M->joints[M->bodies[b].joint].parent;
    if (p == AP_GROUND) return b;
    b = p;
  }
}

#define GROUP_MAX 16

/* A vehicle: its chassis' root (root[0]) and the roots of plane-contact bodies joined to the
 * group by loop constraints (planar chassis only). */
typedef struct lgroup {
  int root[GROUP_MAX], n;
} lgroup;

static int in_group(const ap_bmodel *M, const lgroup *g, int body) {
  for (int i = 0; body >= 0 && i < g->n; i++)
    if (ap_bm_in_subtree(M, body, g->root[i])) return 1;
  return 0;
}

static int is_plane_root(const ap_bmodel *M, int b) {
  return b >= 0 && M->joints[M->bodies[b].joint].kind == AP_JOINT_PLANE_CONTACT &&
         M->joints[M->bodies[b].joint].parent == AP_GROUND;
}

/* Grows the group of chassis `root` by the plane-contact bodies a loop joins to it. */
static void group_of(const ap_bmodel *M, int root, lgroup *g) {
  g->root[0] = root, g->n = 1;
  if (M->joints[M->bodies[root].joint].kind != AP_JOINT_PLANAR) return;
  for (int grew = 1; grew;) {
    grew = 0;
    for (int ci = 0; ci < M->nc && g->n < GROUP_MAX; ci++) {
      const ap_mcon *c = &M->cons[ci];
      if (c->def.body < 0 || c->def.body2 < 0) continue;
      int a = chassis_of(M, c->def.body), b = chassis_of(M, c->def.body2);
      int ina = in_group(M, g, a), inb = in_group(M, g, b);
      if (ina == inb) continue;
      int other = ina ? b : a;
      if (!is_plane_root(M, other)) continue;
      g->root[g->n++] = other, grew = 1;
    }
  }
}

/* 1 when contact c counts in group g: a wheel contact in it, or the rolling contact of one of
 * its plane-contact bodies. */
static int group_contact(const ap_bmodel *M, const lgroup *g, const ap_mcon *c) {
  if (!c->kind->contact || !in_group(M, g, c->def.body)) return 0;
  return c->wheel >= 0 || is_plane_root(M, c->def.body);
}

void ap_bm_contact_point(const ap_bmodel *M, double *S, const ap_mcon *c, double *p) {
  kbody C = ap_kin_body(M, S, c->def.body);
  if (c->wheel < 0) {   /* a plane-contact body: the joint's contact vector */
    kjoint J = ap_kin_joint(M, S, M->bodies[c->def.body].joint);
    for (int i = 0; i < 3; i++) p[i] = C.o[i] + J.rc[i];
    p[2] = 0.0;
    return;
  }
  kwheel W = ap_contact_geom(M, S, c);
  for (int i = 0; i < 3; i++) p[i] = C.o[i] + W.rc[i];
}

/* sum over the subtree of the com force m a and its moment about o plus the rate of the
 * angular momentum about the com, at the accelerations v'. */
static void inertial_wrench(const ap_bmodel *M, double *S, const double *vd, const lgroup *g,
                            const double *o, double *F, double *T) {
  int k = M->k;
  memset(F, 0, 3 * sizeof *F), memset(T, 0, 3 * sizeof *T);
  for (int b = 0; b < M->nb; b++) {
    if (!in_group(M, g, b)) continue;
    kbody C = ap_kin_body(M, S, b);
    double a[3], al[3], t[3], f[3], x[3], Iw[3];
    v3_copy(C.ao, a);                     /* com bias: ao + al x rc + w x (w x rc) */
    v3_cross_add(C.al, C.rcom, a);
    v3_cross(C.w, C.rcom, t);
    v3_cross_add(C.w, t, a);
    v3_copy(C.al, al);
    for (int col = 0; col < k; col++) {
      v3_axpy(vd[col], C.Jc + 3 * col, a);
      v3_axpy(vd[col], C.Jw + 3 * col, al);
    }
    for (int i = 0; i < 3; i++) f[i] = M->bodies[b].mass * a[i], x[i] = C.o[i] + C.rcom[i];
    ap_bm_add_force(f, x, o, F, T);
    m3_mul_v(C.Iw, al, t);
    v3_axpy(1.0, t, T);
    m3_mul_v(C.Iw, C.w, Iw);
    v3_cross_add(C.w, Iw, T);
  }
}

/* y = S^+ m for the symmetric 2 x 2 S (Saa, Sab, Sbb); returns its rank (relative tol). */
static int pinv2(double Saa, double Sab, double Sbb, const double *m, double *y) {
  double h = 0.5 * (Saa + Sbb), d = hypot(0.5 * (Saa - Sbb), Sab), l1 = h + d, l2 = h - d;
  y[0] = y[1] = 0.0;
  if (!(l1 > 0)) return 0;
  if (l2 > 1e-10 * l1) {
    double det = Saa * Sbb - Sab * Sab;
    y[0] = (Sbb * m[0] - Sab * m[1]) / det, y[1] = (Saa * m[1] - Sab * m[0]) / det;
    return 2;
  }
  double e[2] = {Sab, l1 - Saa};          /* eigenvector of l1 */
  if (hypot(e[0], e[1]) < 1e-300) e[0] = l1 - Sbb, e[1] = Sab;
  double en = hypot(e[0], e[1]);
  e[0] /= en, e[1] /= en;
  double s = (e[0] * m[0] + e[1] * m[1]) / l1;
  y[0] = s * e[0], y[1] = s * e[1];
  return 1;
}

/* 1 when the contact rows .z of the group (rows zr, nz of them) are independent of each other
 * and of every other row of A (b x k, ld b): their multipliers are then unique. Modified
 * Gram-Schmidt on the rows, the others first, relative tolerance 1e-9. */
static int z_rows_independent(const double *A, int b, int k, const int *zr, int nz) {
  double *Q = malloc(((size_t)b * k + 1) * sizeof *Q);
  int nq = 0, ok = 1;
  if (!Q) return 0;
  for (int pass = 0; pass < 2 && ok; pass++)
    for (int r = 0; r < b && ok; r++) {
      int isz = 0;
      for (int j = 0; j < nz; j++) isz |= zr[j] == r;
      if (isz != pass) continue;
      double *x = Q + (size_t)nq * k, n0 = 0.0, n1 = 0.0;
      for (int c = 0; c < k; c++) x[c] = A[r + (size_t)c * b], n0 += x[c] * x[c];
      for (int j = 0; j < nq; j++) {
        const double *e = Q + (size_t)j * k;
        double dot = 0.0;
        for (int c = 0; c < k; c++) dot += e[c] * x[c];
        for (int c = 0; c < k; c++) x[c] -= dot * e[c];
      }
      for (int c = 0; c < k; c++) n1 += x[c] * x[c];
      if (n1 > 1e-18 * n0 && n1 > 0) {
        for (int c = 0; c < k; c++) x[c] /= sqrt(n1);
        nq++;
      } else if (pass) {
        ok = 0;
      }
    }
  free(Q);
  return ok;
}

/* The contacts of group g: their number, their centroid c (3) and their rows .z (the first
 * 64; -1 for a plane-contact body, which has none) into zr. */
static int contacts_of(const ap_bmodel *M, double *S, const lgroup *g, double *c, int *zr) {
  int n = 0;
  double p[3];
  c[0] = c[1] = c[2] = 0.0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *w = &M->cons[ci];
    if (!group_contact(M, g, w)) continue;
    ap_bm_contact_point(M, S, w, p);
    v3_axpy(1.0, p, c);
    if (zr && n < 64) zr[n] = w->wheel >= 0 ? w->row + w->hrow : -1;
    n++;
  }
  for (int i = 0; n && i < 3; i++) c[i] /= n;
  return n;
}

/* The effects' and the constraints' wrench on group g about o: the sum over its roots (a
 * spring or a loop between two members counts once on each side and cancels). */
static int group_wrench(const ap_bmodel *M, double *S, const ap_data *d, const double *lam,
                        const lgroup *g, const double *o, double *Fe, double *Te, double *Fc,
                        double *Tc) {
  memset(Fe, 0, 3 * sizeof *Fe), memset(Te, 0, 3 * sizeof *Te);
  memset(Fc, 0, 3 * sizeof *Fc), memset(Tc, 0, 3 * sizeof *Tc);
  for (int i = 0; i < g->n; i++) {
    double F[3], T[3];
    int rc = ap_eff_subtree_wrench(M, S, d->t, d->v, g->root[i], o, F, T);
    if (rc != AP_OK) return rc;
    v3_axpy(1.0, F, Fe), v3_axpy(1.0, T, Te);
    rc = ap_con_subtree_wrench(M, S, lam, g->root[i], -1, o, F, T);
    if (rc != AP_OK) return rc;
    v3_axpy(1.0, F, Fc), v3_axpy(1.0, T, Tc);
  }
  return AP_OK;
}

/* The load of contact `constraint` redistributed from the group's balance at the
 * accelerations vd and multipliers lam (the n contacts of group g, centroid c): affine in
 * (vd, lam). *rank gets the rank of S. */
static int redistributed(const ap_model *m, const ap_data *d, const double *vd,
                         const double *lam, int constraint, const lgroup *g, int planar, int n,
                         const double *c, double *normal, int *rank) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *me = &M->cons[constraint];
  double *S = ap_bm_scratch(d), p[3];
  double Fi[3], Ti[3], Fe[3], Te[3], Fc[3], Tc[3];
  inertial_wrench(M, S, vd, g, c, Fi, Ti);
  int rc = group_wrench(M, S, d, lam, g, c, Fe, Te, Fc, Tc);
  if (rc != AP_OK) return rc;
  double Saa = 0, Sab = 0, Sbb = 0, ai = 0, bi = 0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *w = &M->cons[ci];
    if (!group_contact(M, g, w)) continue;
    double a, b;
    ap_bm_contact_point(M, S, w, p);
    if (!planar && w->wheel >= 0) {   /* the rows .z back out: redistributed */
      double f[3] = {0, 0, -lam[w->row + w->hrow]};
      ap_bm_add_force(f, p, c, Fc, Tc);
    }
    a = p[0] - c[0], b = p[1] - c[1];
    Saa += a * a, Sab += a * b, Sbb += b * b;
    if (ci == constraint) ai = a, bi = b;
  }
  double RM[3], mm[2], y[2];
  for (int i = 0; i < 3; i++) RM[i] = Ti[i] - Te[i] - Tc[i];
  mm[0] = -RM[1], mm[1] = RM[0];
  *rank = pinv2(Saa, Sab, Sbb, mm, y);
  *normal = (Fi[2] - Fe[2] - Fc[2]) / n + ai * y[0] + bi * y[1];
  if (planar && me->wheel >= 0) *normal += lam[me->row + me->hrow];
  return AP_OK;
}

/* The group of contact c's vehicle: its chassis' own, or for a body on a plane-contact joint
 * the group of a planar chassis that a loop joins it to (0: none, c stands alone). */
static int group_of_contact(const ap_bmodel *M, const ap_mcon *c, lgroup *g) {
  int root = chassis_of(M, c->def.body);
  if (c->wheel >= 0) return group_of(M, root, g), 1;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *l = &M->cons[ci];
    if (l->def.body < 0 || l->def.body2 < 0) continue;
    int a = chassis_of(M, l->def.body), b = chassis_of(M, l->def.body2);
    int other = a == root ? b : b == root ? a : -1;
    if (other < 0 || other == root) continue;
    if (M->joints[M->bodies[other].joint].kind != AP_JOINT_PLANAR) continue;
    group_of(M, other, g);
    if (in_group(M, g, c->def.body)) return 1;
  }
  return 0;
}

int ap_bm_wheel_by_load(const ap_bmodel *M, const ap_mcon *c) {
  return c->wheel >= 0 &&
         M->joints[M->bodies[chassis_of(M, c->def.body)].joint].kind == AP_JOINT_PLANAR;
}

int ap_bm_wheel_load_at(const ap_model *m, const ap_data *d, const double *vd,
                        const double *lam, int constraint, double *normal, int *unique) {
  const ap_bmodel *M = ap_bm(m);
  lgroup g;
  int r = 0;
  double c[3];
  group_of(M, chassis_of(M, M->cons[constraint].def.body), &g);
  int n = contacts_of(M, ap_bm_scratch(d), &g, c, NULL);
  int rc = redistributed(m, d, vd, lam, constraint, &g, 1, n, c, normal, &r);
  if (unique) *unique = n <= r + 1;
  return rc;
}

int ap_bm_wheel_load(const ap_model *m, const ap_data *d, const double *lam, int constraint,
                     double *normal, ap_load_kind *kind, int *count) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *me = &M->cons[constraint];
  lgroup g;
  int zr[64], r;
  if (!group_of_contact(M, me, &g)) return AP_ERR_ARG;
  int planar = M->joints[M->bodies[g.root[0]].joint].kind == AP_JOINT_PLANAR;
  double c[3];
  int n = contacts_of(M, ap_bm_scratch(d), &g, c, zr);
  if (count) *count = n;
  if (!planar && n <= 64 && z_rows_independent(d->A, M->b, M->k, zr, n)) {
    *normal = lam[me->row + me->hrow];   /* the contact row's own multiplier: unique */
    *kind = AP_LOAD_UNIQUE;
    return AP_OK;
  }
  int rc = redistributed(m, d, d->vdot, lam, constraint, &g, planar, n, c, normal, &r);
  *kind = n > r + 1 || !planar ? AP_LOAD_MIN_NORM : r < 2 ? AP_LOAD_JOINT : AP_LOAD_UNIQUE;
  return rc;
}

int ap_bm_plane_in_group(const ap_bmodel *M, const ap_mcon *c) {
  lgroup g;
  return c->wheel < 0 && c->kind->contact && is_plane_root(M, c->def.body) &&
         group_of_contact(M, c, &g);
}
