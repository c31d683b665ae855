/* The tree path of body models (lib/model/tree_*.c) against the dense body evaluator at the
 * same state: a0, h, Q, gamma, g x, A x + a0 and N v agree to round-off, and the tree's basis,
 * particular solutions and reduced metric satisfy A B = 0, A b0 = -a0, A w = gamma and
 * G_t = B_t^T g B_t with the dense A and g. Then the core's structured pipeline
 * (lib/core/structured.c) against ap_forward: v' and q' at speeds on the constraints, v from
 * e' (minimal mode's v = B e' + b0), the projection of perturbed speeds, the kinetic energy and
 * the constraint residual.
 *
 * Models: the car with N trailers and N rolling disks of bench_scaling, and a rig that walks
 * every element the tree path takes: knife edges that the body's own joint cannot satisfy (two
 * wheels spinning on one axle: their rows move to the cart, one of them redundant), a
 * prescribed speed, a ball joint with a driven revolute below it (rheonomic twists), a free
 * body, a disk rolling without spin on a turntable whose rate changes, gravity, a spring to
 * the ground, joint damping, a wrench callback and a user effect. States are random (unit
 * quaternions, the disk well off lying flat). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "core/core.h"
#include "core/structured.h"
#include "model/tree_model.h"

#define TOL 1e-12

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void) {
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 2685821657736338717ull) >> 11) * 0x1.0p-52 - 1.0;
}

static void ok(int rc, const char *what, ap_builder *b) {
  if (rc != AP_OK) {
    fprintf(stderr, "%s: %s (%s)\n", what, ap_strerror(rc), b ? ap_builder_message(b) : "");
    exit(1);
  }
}

static int box(ap_builder *b, const char *name, double m, double cx, double cz) {
  ap_body_def d = ap_body_def_default();
  int id = -1;
  d.name = name, d.mass = m, d.com[0] = cx, d.com[2] = cz;
  d.inertia[0] = 0.5 * m, d.inertia[4] = 0.6 * m, d.inertia[8] = 0.8 * m;
  d.inertia[1] = d.inertia[3] = 0.05 * m;
  ok(ap_builder_add_body(b, &d, &id), name, b);
  return id;
}

static int joint(ap_builder *b, const char *name, ap_joint_kind kind, int parent, int child,
                 double px, double py, double pz) {
  ap_joint_def j = ap_joint_def_default();
  int id = -1;
  j.name = name, j.kind = kind, j.parent = parent, j.child = child;
  j.parent_frame.pos[0] = px, j.parent_frame.pos[1] = py, j.parent_frame.pos[2] = pz;
  ok(ap_builder_add_joint(b, &j, &id), name, b);
  return id;
}

static void knife(ap_builder *b, const char *name, int body, double px, double pz) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = name, c.kind = AP_CON_KNIFE_EDGE, c.body = body;
  c.point[0] = px, c.point[2] = pz;
  ok(ap_builder_add_constraint(b, &c, NULL), name, b);
}

static ap_model *compile(ap_builder *b) {
  ap_model *m = NULL;
  ok(ap_builder_set_path(b, AP_PATH_DENSE), "path", b);   /* the reference; plans made here */
  ok(ap_builder_compile(b, &m), "compile", b);
  ap_builder_free(b);
  return m;
}

static ap_model *trailers(int N) {
  ap_builder *b = NULL;
  char name[32];
  ok(ap_builder_create("trailers", &b), "builder", NULL);
  int prev = box(b, "car", 1000.0, 1.0, 0.0);
  joint(b, "car", AP_JOINT_PLANAR, AP_GROUND, prev, 0, 0, 0);
  knife(b, "car.axle", prev, 0.0, 0.0);
  for (int i = 0; i < N; i++) {
    snprintf(name, sizeof name, "trailer%d", i + 1);
    int id = box(b, name, 300.0, 0.4, 0.0);
    ap_joint_def j = ap_joint_def_default();
    j.name = name, j.kind = AP_JOINT_REVOLUTE, j.parent = prev, j.child = id;
    j.parent_frame.pos[0] = -0.5, j.child_frame.pos[0] = 1.2;
    ok(ap_builder_add_joint(b, &j, NULL), name, b);
    snprintf(name, sizeof name, "trailer%d.axle", i + 1);
    knife(b, name, id, 0.0, 0.0);
    prev = id;
  }
  return compile(b);
}

static ap_model *disks(int N) {
  ap_builder *b = NULL;
  char name[32];
  ok(ap_builder_create("disks", &b), "builder", NULL);
  for (int i = 0; i < N; i++) {
    snprintf(name, sizeof name, "disk%d", i + 1);
    ap_body_def d = ap_body_def_default();
    d.name = name, d.shape.kind = AP_SHAPE_DISK, d.shape.radius = 0.5;
    ok(ap_body_def_uniform(&d, 1.0), name, b);
    int id = -1;
    ok(ap_builder_add_body(b, &d, &id), name, b);
    joint(b, name, AP_JOINT_PLANE_CONTACT, AP_GROUND, id, 0, 0, 0);
    ap_constraint_def c = ap_constraint_def_default();
    snprintf(name, sizeof name, "roll%d", i + 1);
    c.name = name, c.kind = AP_CON_ROLLING, c.body = id;
    ok(ap_builder_add_constraint(b, &c, NULL), name, b);
  }
  ap_effect_def e = ap_effect_def_default();
  ok(ap_builder_add_effect(b, &e, NULL), "gravity", b);
  return compile(b);
}

static int drive(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.3 * sin(2 * t), f[1] = 0.6 * cos(2 * t), f[2] = -1.2 * sin(2 * t);
  return 0;
}
static int omega(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.5 + 0.1 * t, f[1] = 0.1;
  return 0;
}
static int spin(double t, double f[3], void *user) {
  (void)user;
  f[0] = 2.0 + 0.3 * t, f[1] = 0.3;
  return 0;
}
static int wrench(double t, double F[3], double T[3], void *user) {
  (void)user;
  F[0] = 1.0 + t, F[2] = -2.0, T[1] = 0.5;
  return 0;
}
static int user_q(double t, const double *q, const double *v, double *Q, void *user) {
  (void)t, (void)q, (void)user;
  Q[0] += -0.1 * v[0];
  return 0;
}

static ap_model *rig(void) {
  ap_builder *b = NULL;
  ok(ap_builder_create("rig", &b), "builder", NULL);
  int cart = box(b, "cart", 20.0, 0.1, 0.0);
  joint(b, "cart", AP_JOINT_PLANAR, AP_GROUND, cart, 0, 0, 0);
  knife(b, "rear", cart, -0.5, 0.0);
  int wl = box(b, "wheelL", 2.0, 0.0, 0.0), wr = box(b, "wheelR", 2.0, 0.0, 0.0);
  for (int s = 0; s < 2; s++) {   /* wheels spin about the axle (y): their knife edges move up */
    ap_joint_def j = ap_joint_def_default();
    j.name = s ? "wheelR" : "wheelL", j.kind = AP_JOINT_REVOLUTE, j.parent = cart;
    j.child = s ? wr : wl, j.axis[0] = 0, j.axis[1] = 1, j.axis[2] = 0;
    j.parent_frame.pos[0] = 0.6, j.parent_frame.pos[1] = s ? -0.4 : 0.4;
    ok(ap_builder_add_joint(b, &j, NULL), j.name, b);
    knife(b, s ? "kR" : "kL", s ? wr : wl, 0.0, -0.2);
  }
  int wrj = 2;   /* joint ids: cart 0, wheelL 1, wheelR 2 */
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "spinR", c.kind = AP_CON_PRESCRIBED_SPEED, c.joint = wrj, c.speed_fn = spin;
  ok(ap_builder_add_constraint(b, &c, NULL), "spinR", b);
  int arm = box(b, "arm", 3.0, 0.2, 0.3);
  joint(b, "arm", AP_JOINT_BALL, cart, arm, 0.0, 0.0, 0.5);
  int tip = box(b, "tip", 1.0, 0.3, 0.0);
  ap_joint_def j = ap_joint_def_default();
  j.name = "tip", j.kind = AP_JOINT_REVOLUTE, j.parent = arm, j.child = tip;
  j.parent_frame.pos[2] = 0.6, j.axis[0] = 1, j.axis[2] = 0, j.drive[0] = drive;
  ok(ap_builder_add_joint(b, &j, NULL), "tip", b);
  knife(b, "tipknife", tip, 0.4, 0.0);   /* the ball joint's speeds take it */
  int fb = box(b, "flyer", 1.5, 0.0, 0.1);
  joint(b, "flyer", AP_JOINT_FREE, AP_GROUND, fb, 0, 0, 0);
  knife(b, "flyerknife", fb, 0.2, 0.0);
  ap_body_def d = ap_body_def_default();
  d.name = "disk", d.shape.kind = AP_SHAPE_DISK, d.shape.radius = 0.3;
  ok(ap_body_def_uniform(&d, 1.2), "disk", b);
  int dk = -1;
  ok(ap_builder_add_body(b, &d, &dk), "disk", b);
  joint(b, "disk", AP_JOINT_PLANE_CONTACT, AP_GROUND, dk, 0, 0, 0);
  c = ap_constraint_def_default();
  c.name = "roll", c.kind = AP_CON_ROLLING, c.body = dk, c.no_spin = 1;
  c.ground.kind = AP_GROUND_TURNTABLE, c.ground.omega_fn = omega, c.ground.center[0] = 0.3;
  ok(ap_builder_add_constraint(b, &c, NULL), "roll", b);
  ap_effect_def e = ap_effect_def_default();
  ok(ap_builder_add_effect(b, &e, NULL), "gravity", b);
  e = ap_effect_def_default();
  e.name = "spring", e.kind = AP_EFFECT_SPRING, e.body = arm, e.point[0] = 0.3;
  e.point2[0] = 1.0, e.point2[2] = 1.0, e.stiffness = 30, e.damping = 2, e.rest_length = 0.5;
  ok(ap_builder_add_effect(b, &e, NULL), "spring", b);
  e = ap_effect_def_default();
  e.name = "damp", e.kind = AP_EFFECT_JOINT_DAMPING, e.joint = 1, e.damping = 0.7;
  ok(ap_builder_add_effect(b, &e, NULL), "damp", b);
  e = ap_effect_def_default();
  e.name = "push", e.kind = AP_EFFECT_APPLIED, e.body = tip, e.point[1] = 0.1, e.wrench = wrench;
  ok(ap_builder_add_effect(b, &e, NULL), "push", b);
  e = ap_effect_def_default();
  e.name = "user", e.kind = AP_EFFECT_USER, e.generalized = user_q;
  ok(ap_builder_add_effect(b, &e, NULL), "user", b);
  return compile(b);
}

/* Random state: coordinates in [-1, 1], quaternions normalized (tilted at most ~35 degrees
 * from their identity, so the disk stands well off flat), speeds in [-1, 1]. */
static void state(const ap_model *m, double *q, double *v) {
  int n = ap_model_n(m), k = ap_model_k(m);
  for (int i = 0; i < n; i++) q[i] = urand();
  for (int i = 0; i < n; i++) {
    const char *nm = ap_model_coord_name(m, i);
    size_t L = strlen(nm);
    if (L > 3 && strcmp(nm + L - 3, ".qw") == 0) {
      double *p = q + i, s = 0;
      p[0] = 1.0, p[1] = 0.3 * urand(), p[2] = 0.3 * urand(), p[3] = urand();
      for (int r = 0; r < 4; r++) s += p[r] * p[r];
      for (int r = 0; r < 4; r++) p[r] /= sqrt(s);
      i += 3;
    }
  }
  for (int c = 0; c < k; c++) v[c] = urand();
}

static double max_abs(int n, const double *x) {
  double mx = 0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

static double diff(int n, const double *a, const double *b) {
  double mx = 0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(a[i] - b[i]));
  return mx;
}

/* Dense A x (+ a0). */
static void dense_A(const ap_data *d, const double *x, const double *a0, double *r) {
  for (int s = 0; s < d->b; s++) {
    r[s] = a0 ? a0[s] : 0.0;
    for (int c = 0; c < d->k; c++) r[s] += d->A[s + (size_t)c * d->b] * x[c];
  }
}

/* The structured pipeline against ap_forward at speeds on the constraints. */
static void check_pipeline(const ap_model *m, const ap_tplan *P, ap_data *dd, ap_data *dt,
                           double t) {
  int n = ap_model_n(m), k = ap_model_k(m), b = ap_model_b(m);
  ap_ops ops;
  ap_st *st = NULL;
  ap_tree_ops(P, &ops);
  AP_CHECK_EQ_INT(ap_st_create(m, &ops, &st), AP_OK);
  double *v1 = calloc((size_t)(3 * k + 1), sizeof(double)), *v2 = v1 + k, *e = v2 + k;
  for (int rep = 0; rep < 3; rep++) {
    state(m, dt->q, dt->v);
    dt->t = t + 0.3 * rep;
    dt->basis = AP_BASIS_PARTITIONED, dt->speeds_from_e = 0;
    AP_CHECK_EQ_INT(ap_st_partition(m, dt, st), AP_OK);
    for (int j = 0; j < dt->l; j++) dt->e[j] = urand(), e[j] = dt->e[j];
    ap_st_speeds(m, dt, st);                       /* v = B e' + b0: on the constraints */
    for (int j = 0; j < dt->l; j++) AP_CHECK_NEAR(dt->v[dt->perm[dt->rank + j]], e[j], 0.0);
    memcpy(dd->q, dt->q, sizeof(double) * (size_t)n);
    memcpy(dd->v, dt->v, sizeof(double) * (size_t)k);
    dd->t = dt->t, dd->basis = AP_BASIS_PARTITIONED, dd->speeds_from_e = 0;
    AP_CHECK_EQ_INT(ap_partition(m, dd), AP_OK);
    AP_CHECK_EQ_INT(ap_forward(m, dd), AP_OK);
    int rc = ap_st_position(m, dt, st);
    if (rc == AP_OK) rc = ap_st_velocity(m, dt, st);
    if (rc == AP_OK) rc = ap_st_acceleration(m, dt, st);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) fprintf(stderr, "%s\n", dt->msg);
    double sv = fmax(1.0, max_abs(k, dd->vdot));
    AP_CHECK_LE(diff(k, dt->vdot, dd->vdot), 1e-11 * sv);
    AP_CHECK_LE(diff(n, dt->qdot, dd->qdot), 1e-12 * fmax(1.0, max_abs(n, dd->qdot)));
    AP_CHECK_NEAR(ap_st_energy(dt, st, dt->v), ap_kinetic_energy(dd, dd->v),
                  1e-12 * fmax(1.0, ap_kinetic_energy(dd, dd->v)));
    AP_CHECK_LE(ap_st_residual(dt, st, dt->v), 1e-12 * fmax(1.0, max_abs(k, dt->v)));
    /* reactions: the generalized constraint forces A^T lambda equal the dense path's */
    AP_CHECK_EQ_INT(ap_st_reactions(m, dt, st), AP_OK);
    AP_CHECK_EQ_INT(ap_fwd_reactions(m, dd), AP_OK);
    for (int c = 0; c < k; c++) {
      v1[c] = v2[c] = 0.0;
      for (int s2 = 0; s2 < b; s2++)
        v1[c] += dd->A[s2 + (size_t)c * b] * dt->lambda[s2], v2[c] += dd->A[s2 + (size_t)c * b] * dd->lambda[s2];
    }
    AP_CHECK_LE(diff(k, v1, v2), 1e-10 * fmax(1.0, max_abs(k, v2)));
    if (dd->rank == b) AP_CHECK_LE(diff(b, dt->lambda, dd->lambda), 1e-9 * fmax(1.0, max_abs(b, dd->lambda)));
    /* body queries: states, point Jacobians, com accelerations at v' */
    ap_tree_ws *tws = st->ws;
    AP_CHECK_EQ_INT(ap_tree_body_eval(m, dt, tws), AP_OK);
    AP_CHECK_EQ_INT(ap_body_eval(m, dd), AP_OK);
    ap_tree_com_accel(tws, dt->vdot, -1, tws->U, NULL);   /* the workspace's own U */
    double *Jw1 = calloc(12 * (size_t)k, sizeof(double)), *Jv1 = Jw1 + 3 * k, *Jw2 = Jv1 + 3 * k,
           *Jv2 = Jw2 + 3 * k, qerr = 0, jerr = 0, aerr = 0, jmax = 1, amax = 1;
    for (int bd = 0; bd < ap_model_body_count(m); bd++) {
      ap_body_state sd;
      ap_body_get_state(m, dd, bd, &sd);
      kbody C = ap_kin_body(&P->shadow, tws->S, bd);
      double vc[3], x[3], p0[3] = {0, 0, 0}, rw[3], rv[3], aw[3], av[3], a1[3], a2[3];
      v3_copy(C.vo, vc);
      v3_cross_add(C.w, C.rcom, vc);
      for (int r = 0; r < 3; r++) {
        qerr = fmax(qerr, fabs(C.o[r] - sd.pos[r]) + fabs(C.w[r] - sd.omega[r]) + fabs(vc[r] - sd.vel[r]));
        x[r] = C.o[r] + C.rcom[r];
      }
      ap_tree_point_jacobian(tws, bd, C.o, Jw1, Jv1);
      ap_body_point_jacobian(m, dd, bd, p0, Jw2, Jv2, rw, rv, aw, av);
      jerr = fmax(jerr, fmax(diff(3 * k, Jw1, Jw2), diff(3 * k, Jv1, Jv2)));
      jmax = fmax(jmax, max_abs(3 * k, Jv2));
      /* com acceleration, dense: Jv(com) v' + av */
      double pc[3];
      m3t_mul_v(C.R, C.rcom, pc);
      ap_body_point_jacobian(m, dd, bd, pc, Jw2, Jv2, rw, rv, aw, av);
      for (int r = 0; r < 3; r++) {
        a2[r] = av[r];
        for (int c = 0; c < k; c++) a2[r] += Jv2[r + 3 * (size_t)c] * dd->vdot[c];
      }
      ap_tree_com_accel(tws, dt->vdot, bd, tws->U, a1);
      aerr = fmax(aerr, diff(3, a1, a2)), amax = fmax(amax, max_abs(3, a2));
      (void)x;
    }
    AP_CHECK_LE(qerr, 1e-12);
    AP_CHECK_LE(jerr, 1e-13 * jmax);
    AP_CHECK_LE(aerr, 1e-11 * amax);
    free(Jw1);
    /* minimal mode: v from e' */
    dt->speeds_from_e = 1;
    rc = ap_st_position(m, dt, st);
    if (rc == AP_OK) rc = ap_st_velocity(m, dt, st);
    if (rc == AP_OK) rc = ap_st_acceleration(m, dt, st);
    AP_CHECK_EQ_INT(rc, AP_OK);
    AP_CHECK_LE(diff(k, dt->vdot, dd->vdot), 1e-11 * sv);
    dt->speeds_from_e = 0;
    /* projection of perturbed speeds, and of a tangent */
    for (int c = 0; c < k; c++) v1[c] = dt->v[c] + 0.01 * urand();
    memcpy(v2, v1, sizeof(double) * (size_t)k);
    double c1 = 0, c2 = 0;
    AP_CHECK_EQ_INT(ap_st_project_here(m, dt, st, v1, &c1), AP_OK);
    dd->basis = AP_BASIS_ORTHONORMAL;
    AP_CHECK_EQ_INT(ap_project_speeds(m, dd, v2, &c2), AP_OK);
    AP_CHECK_LE(diff(k, v1, v2), 1e-12 * fmax(1.0, max_abs(k, v2)));
    AP_CHECK_NEAR(c1, c2, 1e-12 * fmax(1.0, c2));
    AP_CHECK_LE(ap_st_residual(dt, st, v1), 1e-12 * fmax(1.0, max_abs(k, v1)));
    (void)b;
  }
  /* completing speeds from given ones: the same as the dense path when they determine the rest */
  int *given = calloc((size_t)k, sizeof(int));
  const char *gname[3] = {".x_dot", ".heading_dot", ".wz"};
  for (int c = 0; c < k; c++)
    for (int g = 0; g < 3; g++) {
      const char *nm = ap_model_speed_name(m, c);
      size_t L = strlen(nm), G = strlen(gname[g]);
      if (L > G && strcmp(nm + L - G, gname[g]) == 0 && (g < 2 ? strncmp(nm, "car", 3) == 0 : 1))
        given[c] = 1;
    }
  for (int c = 0; c < k; c++)   /* disks: all three angular speeds given */
    if (strstr(ap_model_speed_name(m, c), "disk") && strstr(ap_model_speed_name(m, c), ".w"))
      given[c] = 1;
  int ng = 0;
  for (int c = 0; c < k; c++) ng += given[c];
  if (ng == k - b) {
    state(m, dt->q, v1);
    memcpy(v2, v1, sizeof(double) * (size_t)k);
    memcpy(dd->q, dt->q, sizeof(double) * (size_t)n);
    AP_CHECK_EQ_INT(ap_body_complete_speeds(m, dd, dd->q, given, v2), AP_OK);
    ap_tree_ws *ws = st->ws;
    AP_CHECK_EQ_INT(ap_tree_complete_speeds(m, dt, ws, given, v1), AP_OK);
    AP_CHECK_LE(diff(k, v1, v2), 1e-12 * fmax(1.0, max_abs(k, v2)));
    printf("  completed %d speeds from %d given\n", k - ng, ng);
  }
  free(given);
  free(v1);
  ap_st_free(st);
}

static void check_model(const ap_model *m, const char *label, double t) {
  int n = ap_model_n(m), k = ap_model_k(m), b = ap_model_b(m);
  ap_tplan *P = NULL;
  char why[256];
  AP_CHECK_EQ_INT(ap_tree_plan_create(m, &P, why, sizeof why), AP_OK);
  if (!P) {
    fprintf(stderr, "%s: %s\n", label, why);
    return;
  }
  ap_data *dd = NULL, *dt = NULL;
  ok(ap_data_create(m, &dd), "data", NULL);
  ok(ap_data_create(m, &dt), "data", NULL);
  double *dbl = malloc(sizeof(double) * P->nd);
  int *ints = malloc(sizeof(int) * (P->ni + 1));
  ap_tree_ws ws;
  ap_tree_ws_init(P, dbl, ints, &ws);
  double *x = calloc((size_t)(4 * k + 2 * b + n + 8), sizeof(double));
  double *y = x + k, *z = y + k, *r1 = z + k, *r2 = r1 + b + 1, *qd = r2 + b + 1, *B = NULL;
  for (int rep = 0; rep < 4; rep++) {
    state(m, dd->q, dd->v);
    dd->t = dt->t = t + rep;
    memcpy(dt->q, dd->q, sizeof(double) * (size_t)n);
    memcpy(dt->v, dd->v, sizeof(double) * (size_t)k);
    dd->basis = AP_BASIS_NONE;
    int rc = ap_tree_position(m, dt, &ws, 1);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) {
      fprintf(stderr, "%s: %s\n", label, dt->msg);
      break;
    }
    /* speeds on the constraints (gamma of redundant rows is consistent only there) */
    for (int j = 0; j < dt->l; j++) x[j] = urand();
    ap_la_tree_solve(&P->T, &ws.g, &ws.W, x, b ? dt->a0 : NULL, dt->v);
    memcpy(dd->v, dt->v, sizeof(double) * (size_t)k);
    ok(ap_fwd_position(m, dd), dd->msg, NULL);
    ok(ap_fwd_velocity(m, dd), dd->msg, NULL);
    ok(ap_tree_velocity(m, dt, &ws), dt->msg, NULL);
    AP_CHECK_LE(dt->resid_gamma, TOL * 100);
    double sa = fmax(1.0, max_abs(b * k, dd->A)), sg = fmax(1.0, max_abs(k * k, dd->g));
    AP_CHECK_LE(diff(b, dt->a0, dd->a0), TOL * fmax(sa, max_abs(b, dd->a0)));
    AP_CHECK_LE(diff(k, dt->h, dd->h), TOL * fmax(1.0, max_abs(k, dd->h)) * 10);
    AP_CHECK_LE(diff(k, dt->Q, dd->Q), TOL * fmax(1.0, max_abs(k, dd->Q)) * 10);
    AP_CHECK_LE(diff(b, dt->gamma, dd->gamma), TOL * fmax(1.0, max_abs(b, dd->gamma)) * 10);
    for (int c = 0; c < k; c++) x[c] = urand();
    ap_tree_gmul(&ws, x, y);
    for (int a = 0; a < k; a++) {
      z[a] = 0;
      for (int c = 0; c < k; c++) z[a] += dd->g[a + (size_t)c * k] * x[c];
    }
    AP_CHECK_LE(diff(k, y, z), TOL * sg * 10);
    ap_tree_amul(&ws, dt, x, 1, r1, NULL);
    dense_A(dd, x, dd->a0, r2);
    AP_CHECK_LE(diff(b, r1, r2), TOL * sa * 10);
    ap_tree_nmul(P, dt->q, dt->v, qd);
    for (int i = 0; i < n; i++) {
      z[0] = 0;
      for (int c = 0; c < k; c++) z[0] += dd->N[i + (size_t)c * n] * dt->v[c];
      AP_CHECK_NEAR(qd[i], z[0], TOL);
    }
    /* b0, w and the blocks */
    dense_A(dd, dt->b0, dd->a0, r1);
    AP_CHECK_LE(max_abs(b, r1), TOL * sa * fmax(1.0, max_abs(k, dt->b0)) * 10);
    dense_A(dd, dt->w, NULL, r1);
    AP_CHECK_LE(diff(b, r1, dd->gamma), TOL * sa * fmax(1.0, max_abs(k, dt->w)) * 10);
    AP_CHECK_EQ_INT(dt->rank, b - (strcmp(label, "rig") == 0));   /* the rig: one redundant */
    const ap_la_tree_work *W = &ws.W;
    int l = W->l;
    free(B);
    B = calloc((size_t)k * (l ? l : 1), sizeof(double));
    for (int tr = 0; tr < P->T.ntree; tr++) {
      int kt = W->kofs[tr + 1] - W->kofs[tr];
      for (int jj = 0; jj < W->lofs[tr + 1] - W->lofs[tr]; jj++)
        for (int rr = 0; rr < kt; rr++)
          B[P->kspeed[W->kofs[tr] + rr] + (size_t)W->lidx[W->lofs[tr] + jj] * k] =
              W->B[W->bofs[tr] + rr + (size_t)jj * kt];
    }
    double err = 0, gerr = 0, gmax = 1;
    for (int j = 0; j < l; j++) {
      dense_A(dd, B + (size_t)j * k, NULL, r1);
      err = fmax(err, max_abs(b, r1));
    }
    AP_CHECK_LE(err, TOL * sa * fmax(1.0, max_abs(k * l, B)) * 10);
    for (int tr = 0; tr < P->T.ntree; tr++) {
      int lt = W->lofs[tr + 1] - W->lofs[tr];
      for (int a = 0; a < lt; a++)
        for (int c2 = 0; c2 < lt; c2++) {
          const double *Ba = B + (size_t)W->lidx[W->lofs[tr] + a] * k,
                       *Bc = B + (size_t)W->lidx[W->lofs[tr] + c2] * k;
          double s = 0;
          for (int p = 0; p < k; p++)
            for (int q2 = 0; q2 < k; q2++) s += Ba[p] * dd->g[p + (size_t)q2 * k] * Bc[q2];
          gmax = fmax(gmax, fabs(s));
          gerr = fmax(gerr, fabs(s - W->G[W->gofs[tr] + a + (size_t)c2 * lt]));
        }
    }
    AP_CHECK_LE(gerr, TOL * gmax * 10);
  }
  printf("%s: n %d, k %d, b %d, trees %d, rank %d, l %d\n", label, n, k, b, P->T.ntree, dt->rank,
         dt->l);
  check_pipeline(m, P, dd, dt, t);
  free(B), free(x), free(dbl), free(ints);
  ap_data_free(dd), ap_data_free(dt);
  ap_tree_plan_free(P);
}

int main(void) {
  ap_model *m = trailers(6);
  check_model(m, "trailers", 0.0);
  ap_model_free(m);
  m = disks(4);
  check_model(m, "disks", 0.0);
  ap_model_free(m);
  m = rig();
  check_model(m, "rig", 0.7);
  ap_model_free(m);
  return ap_check_finish("test_tree_bodies");
}
