/* Reference problems (docs/references.md) against the engine; the harness (running a case in
 * every mode and method, the targets, the closed-form checker) is in refcase.c.
 *
 * Part 1 checks the hand-written systems of refsys.h on their own, without integrating: the
 * closed forms satisfy q' = v, the constraints and the equations of motion (g v' + h - Q lies in
 * the range of A^T) by central differences along the exact motion, gamma = A v' there, the
 * printed sleigh sample, Kron's C^T M C = printed g, and the Hoffmann equilibrium.
 *
 * Part 2 integrates every problem at several parameter sets and initial conditions in both
 * modes (minimal, projected) with several adaptive steppers at rtol 1e-11, atol 1e-13, with
 * outputs every 0.5 s over 20 s, and asserts the targets of refcase.c (positions within
 * 1e3 rtol of the closed form, constraint residuals, conserved quantities) and mode-specific
 * facts: partition switches of the spinning knife edge, the knife-edge multiplier, the
 * sleigh's two bias sources, the Hoffmann reduced vs primitive systems, and errors that shrink
 * with rtol. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "refcase.h"

/* ------------------------------------------------------------------------------------------ */
/* Problem contexts and their exact/invariant adapters.                                       */

typedef struct knife_ctx { rs_knife p; double q0[3], v0[3]; } knife_ctx;
static void knife_ex(const void *c, double t, double *q, double *v) {
  const knife_ctx *k = c;
  rs_knife_exact(&k->p, k->q0, k->v0, t, q, v, NULL);
}
/* lambda = -m w u - m G sin(phi): scale m (|w u| + G). */
static void knife_lam(const void *c, double t, double *lam, double *scale) {
  const knife_ctx *k = c;
  double v[3], G = k->p.grav * sin(k->p.alpha);
  rs_knife_exact(&k->p, k->q0, k->v0, t, NULL, v, lam);
  *scale = k->p.m * (fabs(v[2]) * hypot(v[0], v[1]) + G);
}
static int knife_inv(const void *c, double t, const double *q, const double *v, double *o,
                     double *sc) {
  const rs_knife *p = &((const knife_ctx *)c)->p;
  (void)t;
  o[0] = rs_knife_energy(p, q, v);
  sc[0] = 0.5 * p->m * (v[0] * v[0] + v[1] * v[1]) + 0.5 * p->J * v[2] * v[2] +
          fabs(p->m * p->grav * q[0] * sin(p->alpha));
  return 1;
}

typedef struct sleigh_ctx { rs_sleigh p; double q0[3], v0[3]; } sleigh_ctx;
static void sleigh_ex(const void *c, double t, double *q, double *v) {
  const sleigh_ctx *s = c;
  rs_sleigh_exact(&s->p, s->q0, s->v0, t, q, v);
}
static int sleigh_inv(const void *c, double t, const double *q, const double *v, double *o,
                      double *sc) {
  (void)t;
  sc[0] = o[0] = rs_sleigh_energy(&((const sleigh_ctx *)c)->p, q, v);
  return 1;
}

typedef struct turn_ctx { rs_turntable p; double q0[5], v0[5]; } turn_ctx;
static void turn_ex(const void *c, double t, double *q, double *v) {
  const turn_ctx *s = c;
  rs_turntable_exact(&s->p, s->q0, s->v0, t, q, v);
}
/* c = z' - i kt Omega z (two reals) and wz. */
static int turn_inv(const void *c, double t, const double *q, const double *v, double *o,
                    double *sc) {
  const rs_turntable *p = &((const turn_ctx *)c)->p;
  double kt = p->kI / (1.0 + p->kI), Om = fabs(rs_turntable_omega(p, t));
  rs_turntable_invariant(p, t, q, v, o);
  o[2] = v[4];
  sc[0] = fabs(v[0]) + kt * Om * fabs(q[1]);
  sc[1] = fabs(v[1]) + kt * Om * fabs(q[0]);
  sc[2] = fabs(v[4]);
  return 3;
}

typedef struct line_ctx { rs_line p; double r0, rd0; } line_ctx;
static void line_r_ex(const void *c, double t, double *q, double *v) {
  const line_ctx *s = c;
  rs_line_exact(&s->p, s->r0, s->rd0, t, q, v);
}
static void line_3d_ex(const void *c, double t, double *q, double *v) {
  const line_ctx *s = c;
  double r, rd;
  rs_line_exact(&s->p, s->r0, s->rd0, t, &r, &rd);
  rs_line_lift(&s->p, t, r, rd, q, v);
}
/* Jacobi integral m (r'^2 - s^2 r^2)/2 + m grav r cos(alpha): scale = the sum of |terms|. */
static int line_r_inv(const void *c, double t, const double *q, const double *v, double *o,
                      double *sc) {
  const rs_line *p = &((const line_ctx *)c)->p;
  double s = p->w * sin(p->alpha);
  (void)t;
  o[0] = rs_line_jacobi(p, q[0], v[0]);
  sc[0] = 0.5 * p->m * (v[0] * v[0] + s * s * q[0] * q[0]) +
          fabs(p->m * p->grav * q[0] * cos(p->alpha));
  return 1;
}
/* E - w L_z: scale = kinetic energy + |potential| + |w L_z|. */
static int line_3d_inv(const void *c, double t, const double *q, const double *v, double *o,
                       double *sc) {
  const rs_line *p = &((const line_ctx *)c)->p;
  (void)t;
  o[0] = rs_line_jacobi_3d(p, q, v);
  sc[0] = 0.5 * p->m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
          fabs(p->m * p->grav * q[2]) + fabs(p->w * p->m * (q[0] * v[1] - q[1] * v[0]));
  return 1;
}

/* Energy with the potential of gravity and of the constant force F; scale = T + sum |V_i|. */
static int hoff_inv(const void *c, double t, const double *q, const double *v, double *o,
                    double *sc) {
  const rs_hoffmann *p = c;
  double vz[2] = {0.0, 0.0};
  (void)t;
  o[0] = rs_hoffmann_energy(p, q, v);   /* q, v: the first two entries are (theta, phi) */
  sc[0] = (o[0] - rs_hoffmann_energy(p, q, vz)) + p->grav * (p->m1 + 2.0 * p->m2) * p->a1 +
          p->grav * p->m2 * p->a2 + fabs(p->F) * (2.0 * p->a1 + p->a2);
  return 1;
}

/* ------------------------------------------------------------------------------------------ */
/* 1. Knife edge.                                                                              */

static void knife_setup(knife_ctx *kc, rcase *c, const char *problem, const char *label,
                        rs_knife p, double x0, double y0, double phi0, double u0, double w0,
                        double t_end) {
  memset(c, 0, sizeof *c);
  kc->p = p;
  rs_knife_initial(x0, y0, phi0, u0, w0, kc->q0, kc->v0);
  rs_knife_system(&kc->p, &c->def);
  memcpy(c->q0, kc->q0, sizeof kc->q0);
  memcpy(c->v0, kc->v0, sizeof kc->v0);
  c->problem = problem;
  c->label = label;
  c->t_end = t_end;
  c->exact = knife_ex;
  c->inv = knife_inv;
  c->lambda = knife_lam;
  c->ctx = kc;
}

static void test_knife(void) {
  knife_ctx kc[3];
  rcase c[3];
  printf("knife edge on an incline\n");
  knife_setup(&kc[0], &c[0], "knife", "knife A", (rs_knife){1.0, 0.5, 9.81, 0.3}, 0.0, 0.0,
              0.3, 1.0, 1.5, T_END);
  knife_setup(&kc[1], &c[1], "knife", "knife B", (rs_knife){2.5, 0.2, 9.81, 0.5}, 1.0, -2.0,
              -1.0, -0.5, -0.8, T_END);
  knife_setup(&kc[2], &c[2], "knife", "knife C (slow, u0 = 0)",
              (rs_knife){0.7, 1.3, 3.7, 0.15}, -0.4, 0.25, 2.0, 0.0, 0.35, T_END);
  for (int i = 0; i < 3; i++) {
    double lam;
    for (double t = 0.3; t < 20.0; t += 6.1) {
      double le;
      check_closed_form(c[i].label, &c[i].def, knife_ex, &kc[i], t, 1e-8, &lam);
      double lsc;
      knife_lam(&kc[i], t, &le, &lsc);
      AP_CHECK_NEAR(lam, le, 1e-8 * fmax(1.0, fabs(le)));
    }
    check_case(&c[i], NULL);
  }
}

/* The spinning skate: w = 20 rad/s for 20 s (~64 turns); two partition switches a turn at
 * least (the dependent speed changes near 45 degrees, 4 times a turn, with hysteresis). */
static void test_knife_spin(void) {
  knife_ctx kc;
  rcase c;
  printf("spinning knife edge\n");
  knife_setup(&kc, &c, "knife-spin", "knife spin w = 20", (rs_knife){1.0, 0.1, 9.81, 0.2}, 0.0,
              0.0, 0.1, 0.5, 20.0, T_END);
  check_case(&c, NULL);
  double turns = 20.0 * T_END / (2.0 * RS_PI);
  for (int ki = 0; ki < N_METHODS; ki++) {
    rrun r;
    run_case(&c, 0, methods[ki], RTOL, ATOL, &r);
    printf("  %s minimal: %ld partition switches over %.1f turns\n", methods[ki],
           r.st.partition_switches, turns);
    AP_CHECK(r.st.partition_switches >= (long)(2.0 * turns));
    AP_CHECK(r.st.restarts >= r.st.partition_switches);
  }
}

/* Errors shrink with rtol: the tolerance-following claim is honest. */
static void test_knife_rtol(void) {
  knife_ctx kc;
  rcase c;
  printf("error vs rtol\n");
  knife_setup(&kc, &c, "knife", "knife A", (rs_knife){1.0, 0.5, 9.81, 0.3}, 0.0, 0.0, 0.3, 1.0,
              1.5, T_END);
  for (int mi = 0; mi < N_MODES; mi++) {
    rrun lo, hi;
    run_case(&c, mi, "dopri5", 1e-8, 1e-10, &lo);
    run_case(&c, mi, "dopri5", RTOL, ATOL, &hi);
    printf("  knife %s dopri5: error %.2e at rtol 1e-8, %.2e at rtol 1e-11\n", mode_names[mi],
           lo.pos_err, hi.pos_err);
    AP_CHECK(lo.pos_err > hi.pos_err);
    AP_CHECK_LE(lo.pos_err, 1e3 * 1e-8);
    AP_CHECK(lo.pos_err > 10.0 * hi.pos_err);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* 2. Chaplygin sleigh.                                                                        */

static void sleigh_setup(sleigh_ctx *sc, rcase *c, const char *label, rs_sleigh p,
                         int explicit_bias, double x0, double y0, double th0, double u0,
                         double w0) {
  memset(c, 0, sizeof *c);
  sc->p = p;
  rs_sleigh_initial(x0, y0, th0, u0, w0, sc->q0, sc->v0);
  rs_sleigh_system(&sc->p, explicit_bias, &c->def);
  memcpy(c->q0, sc->q0, sizeof sc->q0);
  memcpy(c->v0, sc->v0, sizeof sc->v0);
  c->problem = "sleigh";
  c->label = label;
  c->t_end = T_END;
  c->exact = sleigh_ex;
  c->inv = sleigh_inv;
  c->ctx = sc;
}

/* The two bias sources at the data level: h and v' at random states. */
static void sleigh_bias_sources(sleigh_ctx *sc) {
  ap_system_def d1, d2;
  ap_model *m1 = NULL, *m2 = NULL;
  ap_data *a = NULL, *b = NULL;
  char msg[256];
  rs_sleigh_system(&sc->p, 0, &d1);
  rs_sleigh_system(&sc->p, 1, &d2);
  AP_CHECK_EQ_INT(ap_model_from_system(&d1, &m1, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_model_from_system(&d2, &m2, msg, sizeof msg), AP_OK);
  if (!m1 || !m2) goto done;
  AP_CHECK_EQ_INT(ap_data_create(m1, &a), AP_OK);
  AP_CHECK_EQ_INT(ap_data_create(m2, &b), AP_OK);
  if (!a || !b) goto done;
  double worst_h = 0.0, worst_vd = 0.0;
  unsigned seed = 12345u;
  for (int trial = 0; trial < 50; trial++) {
    double x[6];
    for (int j = 0; j < 6; j++) {
      seed = seed * 1103515245u + 12345u;
      x[j] = 4.0 * ((seed >> 8) & 0xffff) / 65535.0 - 2.0;
    }
    ap_data *ds[2] = {a, b};
    const ap_model *ms[2] = {m1, m2};
    for (int i = 0; i < 2; i++) {
      ap_data *d = ds[i];
      d->t = 0.0;
      d->basis = AP_BASIS_ORTHONORMAL;
      d->speeds_from_e = 0;
      rs_sleigh_initial(x[0], x[1], 3.0 * x[2], x[3], x[4], d->q, d->v);
      AP_CHECK_EQ_INT(ap_forward(ms[i], d), AP_OK);
    }
    for (int j = 0; j < 3; j++) {
      worst_h = fmax(worst_h, fabs(a->h[j] - b->h[j]));
      worst_vd = fmax(worst_vd, fabs(a->vdot[j] - b->vdot[j]));
    }
  }
  printf("  sleigh Christoffel vs explicit bias (data level): |dh| %.2e, |dv'| %.2e\n", worst_h,
         worst_vd);
  AP_CHECK_LE(worst_h, 1e-14);
  AP_CHECK_LE(worst_vd, 1e-14);
done:
  ap_data_free(a);
  ap_data_free(b);
  ap_model_free(m1);
  ap_model_free(m2);
}

static void test_sleigh(void) {
  sleigh_ctx sc[4];
  rcase c[4];
  printf("Chaplygin sleigh\n");
  /* The printed sample first: u, w, theta, x, y at t = 15. */
  sleigh_setup(&sc[0], &c[0], "sleigh printed", (rs_sleigh){1.0, 1.0, 1.0}, 0, 0.0, 0.0, RS_PI,
               0.1, 0.2);
  double q[3], v[3];
  rs_sleigh_exact(&sc[0].p, sc[0].q0, sc[0].v0, 15.0, q, v);
  double u = v[0] * cos(q[2]) + v[1] * sin(q[2]);
  AP_CHECK_NEAR(u, 0.29668571025517837, 1e-14);
  AP_CHECK_NEAR(v[2], 0.03144510558402052, 1e-14);
  AP_CHECK_NEAR(q[2], 4.672022704815886, 1e-14);
  AP_CHECK_NEAR(q[0], -1.5814737061340092, 1e-12);
  AP_CHECK_NEAR(q[1], -3.0441567427652534, 1e-12);
  printf("  printed sample at t = 15: x err %.2e, y err %.2e\n", fabs(q[0] + 1.5814737061340092),
         fabs(q[1] + 3.0441567427652534));

  sleigh_setup(&sc[1], &c[1], "sleigh printed (bias)", (rs_sleigh){1.0, 1.0, 1.0}, 1, 0.0, 0.0,
               RS_PI, 0.1, 0.2);
  sleigh_setup(&sc[2], &c[2], "sleigh B (backward)", (rs_sleigh){2.0, 0.3, 0.4}, 0, 1.0, 2.0,
               0.7, -0.5, 1.0);
  sleigh_setup(&sc[3], &c[3], "sleigh C", (rs_sleigh){0.5, 0.1, 0.25}, 1, -1.0, 0.5, -2.0, 0.3,
               -2.0);
  for (int i = 0; i < 4; i++) {
    for (double t = 0.2; t < 20.0; t += 4.9)
      check_closed_form(c[i].label, &c[i].def, sleigh_ex, &sc[i], t, 1e-8, NULL);
    check_case(&c[i], NULL);
  }
  /* Trajectories with the two bias sources agree to round-off, amplified by the step-size
   * control (a change of 1e-16 in h changes the accepted steps slightly): far below the
   * integration error, so the bound is rtol rather than POS_TOL. */
  for (int mi = 0; mi < N_MODES; mi++) {
    rrun r0, r1;
    double diff = 0.0;
    run_case(&c[0], mi, "dopri5", RTOL, ATOL, &r0);
    run_case(&c[1], mi, "dopri5", RTOL, ATOL, &r1);
    for (int i = 0; i < r0.nout && i < r1.nout; i++)
      for (int j = 0; j < 3; j++) diff = fmax(diff, fabs(r0.q[i][j] - r1.q[i][j]));
    printf("  sleigh %s: Christoffel vs explicit bias trajectories differ by %.2e\n",
           mode_names[mi], diff);
    AP_CHECK_LE(diff, RTOL);
  }
  sleigh_bias_sources(&sc[2]);
}

/* ------------------------------------------------------------------------------------------ */
/* 3. Ball on a turntable.                                                                     */

static void turn_setup(turn_ctx *tc, rcase *c, const char *problem, const char *label,
                       rs_turntable p, double x0, double y0, double wx, double wy, double wz) {
  memset(c, 0, sizeof *c);
  tc->p = p;
  rs_turntable_initial(&tc->p, x0, y0, wx, wy, wz, tc->q0, tc->v0);
  rs_turntable_system(&tc->p, &c->def);
  memcpy(c->q0, tc->q0, sizeof tc->q0);
  memcpy(c->v0, tc->v0, sizeof tc->v0);
  c->problem = problem;
  c->label = label;
  c->t_end = T_END;
  c->exact = turn_ex;
  c->inv = turn_inv;
  c->ctx = tc;
}

static void test_turntable(void) {
  turn_ctx tc[4];
  rcase c[4];
  printf("ball on a turntable\n");
  turn_setup(&tc[0], &c[0], "turntable", "turntable solid", (rs_turntable){1.0, 0.1, 0.4, 2.0, 0.0},
             0.3, -0.1, 1.0, -2.0, 3.0);
  turn_setup(&tc[1], &c[1], "turntable", "turntable hollow",
             (rs_turntable){0.3, 0.05, 2.0 / 3.0, -1.5, 0.0}, -0.2, 0.4, -3.0, 0.5, -1.0);
  turn_setup(&tc[2], &c[2], "turntable-rheo", "turntable Omega(t) solid",
             (rs_turntable){1.0, 0.1, 0.4, 0.5, 0.1}, 0.3, -0.1, 1.0, -2.0, 3.0);
  turn_setup(&tc[3], &c[3], "turntable-rheo", "turntable Omega(t) hollow",
             (rs_turntable){2.0, 0.2, 2.0 / 3.0, -1.0, 0.15}, 0.5, 0.5, 0.3, 0.8, 0.0);
  /* The constant-Omega closed form is the reference's circle: radius |z0'|/kappa, centre
   * z0 + i z0'/kappa. */
  {
    double kap = 0.4 / 1.4 * 2.0, q[5], v[5];
    double cx = tc[0].q0[0] - tc[0].v0[1] / kap, cy = tc[0].q0[1] + tc[0].v0[0] / kap;
    double rad = hypot(tc[0].v0[0], tc[0].v0[1]) / kap;
    for (double t = 0.0; t < 20.0; t += 1.7) {
      rs_turntable_exact(&tc[0].p, tc[0].q0, tc[0].v0, t, q, v);
      AP_CHECK_NEAR(hypot(q[0] - cx, q[1] - cy), rad, 1e-14);
    }
  }
  for (int i = 0; i < 4; i++) {
    for (double t = 0.3; t < 20.0; t += 4.7)
      check_closed_form(c[i].label, &c[i].def, turn_ex, &tc[i], t, 1e-8, NULL);
    check_case(&c[i], NULL);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* 4. Particle on a rotating inclined line.                                                    */

static void line_setup(line_ctx *lc, rcase *c, int three_d, const char *label, rs_line p,
                       double r0, double rd0) {
  memset(c, 0, sizeof *c);
  lc->p = p;
  lc->r0 = r0;
  lc->rd0 = rd0;
  if (three_d) {
    rs_line_3d_system(&lc->p, &c->def);
    rs_line_lift(&lc->p, 0.0, r0, rd0, c->q0, c->v0);
    c->exact = line_3d_ex;
    c->inv = line_3d_inv;
    c->problem = "line-3d";
  } else {
    rs_line_reduced_system(&lc->p, &c->def);
    c->q0[0] = r0;
    c->v0[0] = rd0;
    c->exact = line_r_ex;
    c->inv = line_r_inv;
    c->problem = "line-reduced";
  }
  c->label = label;
  c->t_end = T_END;
  c->ctx = lc;
}

static void test_line(void) {
  line_ctx lc[4];
  rcase c[4];
  printf("particle on a rotating inclined line\n");
  line_setup(&lc[0], &c[0], 0, "line A reduced", (rs_line){1.0, 9.81, 0.6, 0.4}, 150.0, 0.0);
  line_setup(&lc[1], &c[1], 1, "line A 3-D", (rs_line){1.0, 9.81, 0.6, 0.4}, 150.0, 0.0);
  line_setup(&lc[2], &c[2], 0, "line B reduced", (rs_line){0.3, 9.81, 1.2, -0.25}, 2.0, 0.5);
  line_setup(&lc[3], &c[3], 1, "line B 3-D", (rs_line){0.3, 9.81, 1.2, -0.25}, 2.0, 0.5);
  for (int i = 0; i < 4; i++) {
    exact_fn ex = c[i].exact;
    for (double t = 0.3; t < 20.0; t += 4.7)
      check_closed_form(c[i].label, &c[i].def, ex, &lc[i], t, 1e-8, NULL);
    check_case(&c[i], NULL);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* 5. Hoffmann's two-rod pendulum.                                                             */

static void hoff_cases(rs_hoffmann *p, const double q2[2], const double v2[2], rcase *red,
                       rcase *prim, const char *lred, const char *lprim) {
  memset(red, 0, sizeof *red);
  memset(prim, 0, sizeof *prim);
  rs_hoffmann_reduced_system(p, &red->def);
  rs_hoffmann_primitive_system(p, &prim->def);
  memcpy(red->q0, q2, 2 * sizeof *q2);
  memcpy(red->v0, v2, 2 * sizeof *v2);
  rs_hoffmann_lift(p, q2, v2, prim->q0, prim->v0);
  red->problem = prim->problem = "hoffmann";
  red->label = lred;
  prim->label = lprim;
  red->t_end = prim->t_end = T_END;
  red->inv = prim->inv = hoff_inv;
  red->ctx = prim->ctx = p;
}

static void test_hoffmann(void) {
  rs_hoffmann P[2] = {
      {1.0, 0.8, 0.5, 0.4, 1.0 * 0.25 / 3.0, 0.8 * 0.16 / 3.0, 9.81, 0.0},
      {2.0, 0.5, 0.3, 0.6, 2.0 * 0.09 / 3.0, 0.5 * 0.36 / 3.0, 9.81, 3.0},
  };
  const double Q0[2][2] = {{0.5, -0.3}, {-0.2, 1.0}}, V0[2][2] = {{0.0, 1.0}, {1.5, -2.0}};
  const char *lab[2][2] = {{"hoffmann A reduced", "hoffmann A primitive"},
                           {"hoffmann B (F=3) reduced", "hoffmann B (F=3) primitive"}};
  printf("Hoffmann's two-rod pendulum\n");
  for (int i = 0; i < 2; i++) {
    /* Kron: C^T M C and C^T F equal the printed g and Q to round-off. */
    double worst = 0.0;
    for (int j = 0; j < 20; j++) {
      double q2[2] = {-3.0 + 0.31 * j, 2.5 - 0.27 * j}, g1[4], g2[4], Q1[2], Q2[2];
      rs_hoffmann_printed(&P[i], q2, g1, Q1);
      rs_hoffmann_connected(&P[i], q2, g2, Q2);
      for (int e = 0; e < 4; e++) worst = fmax(worst, fabs(g1[e] - g2[e]) / fabs(g1[0]));
      for (int e = 0; e < 2; e++) worst = fmax(worst, fabs(Q1[e] - Q2[e]) / (P[i].grav * P[i].m1));
    }
    printf("  Kron C^T M C, C^T F vs printed g, Q: %.2e relative\n", worst);
    AP_CHECK_LE(worst, 1e-15);
    /* The reduced h from dg/dq equals C^T M C' v of the primitive system:
     * h = 2 m2 a1 a2 sin(theta - phi) (phi'^2, -theta'^2). */
    ap_system_def red_def;
    rs_hoffmann_reduced_system(&P[i], &red_def);
    double worst_h = 0.0;
    for (int j = 0; j < 20; j++) {
      double q2[2] = {-3.0 + 0.31 * j, 2.5 - 0.27 * j}, v2[2] = {1.0 - 0.1 * j, 0.3 + 0.2 * j};
      double h[2], K = 2.0 * P[i].m2 * P[i].a1 * P[i].a2 * sin(q2[0] - q2[1]);
      christoffel_h(&red_def, 0.0, q2, v2, h);
      worst_h = fmax(worst_h, fabs(h[0] - K * v2[1] * v2[1]));
      worst_h = fmax(worst_h, fabs(h[1] + K * v2[0] * v2[0]));
    }
    AP_CHECK_LE(worst_h, 1e-14);

    rcase red, prim;
    static rrun ra[N_MODES][N_METHODS], rb[N_MODES][N_METHODS];
    hoff_cases(&P[i], Q0[i], V0[i], &red, &prim, lab[i][0], lab[i][1]);
    check_case(&red, ra);
    check_case(&prim, rb);
    /* Reduced vs primitive + connection: (theta, phi) agree within POS_TOL. */
    for (int mi = 0; mi < N_MODES; mi++) {
      for (int ki = 0; ki < N_METHODS; ki++) {
        const rrun a = ra[mi][ki], b = rb[mi][ki];
        double diff = 0.0;
        AP_CHECK_EQ_INT(a.nout, b.nout);
        for (int o = 0; o < a.nout && o < b.nout; o++)
          for (int j = 0; j < 2; j++) diff = fmax(diff, fabs(a.q[o][j] - b.q[o][j]));
        printf("  %s %s %s: reduced vs primitive (theta, phi) differ by %.2e\n", lab[i][0],
               mode_names[mi], methods[ki], diff);
        AP_CHECK_LE(diff, POS_TOL);
        note_pos("hoffmann", mi, diff);
      }
    }
  }
  /* Equilibrium under F: Q(theta*, phi*) = 0 and a run started there stays there. */
  rs_hoffmann *p = &P[1];
  double qs[2], vz[2] = {0.0, 0.0}, g[4], Q[2];
  rs_hoffmann_equilibrium(p, qs);
  rs_hoffmann_printed(p, qs, g, Q);
  AP_CHECK_LE(fabs(Q[0]), 1e-14 * p->grav * (p->m1 + 2.0 * p->m2) * p->a1);
  AP_CHECK_LE(fabs(Q[1]), 1e-14 * p->grav * p->m2 * p->a2);
  rcase red, prim;
  hoff_cases(p, qs, vz, &red, &prim, "hoffmann equilibrium reduced",
             "hoffmann equilibrium primitive");
  for (int mi = 0; mi < N_MODES; mi++) {
    rrun a, b;
    double drift = 0.0;
    run_case(&red, mi, "dopri5", RTOL, ATOL, &a);
    run_case(&prim, mi, "verner6", RTOL, ATOL, &b);
    for (int o = 0; o < a.nout; o++)
      for (int j = 0; j < 2; j++) drift = fmax(drift, fabs(a.q[o][j] - qs[j]));
    for (int o = 0; o < b.nout; o++)
      for (int j = 0; j < 2; j++) drift = fmax(drift, fabs(b.q[o][j] - qs[j]));
    printf("  equilibrium (%.6f, %.6f) %s: drift %.2e\n", qs[0], qs[1], mode_names[mi], drift);
    AP_CHECK(a.ok && b.ok);
    AP_CHECK_LE(drift, 1e-12);
  }
}

int main(void) {
  double t0 = now();
  test_knife();
  test_knife_spin();
  test_knife_rtol();
  test_sleigh();
  test_turntable();
  test_line();
  test_hoffmann();
  report_worst();
  printf("total %.2f s\n", now() - t0);
  return ap_check_finish("reference");
}