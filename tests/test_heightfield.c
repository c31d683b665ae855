/* Terrain: rolling on a height field z = h(x, y) (ap_ground_motion.height_fn; scenes:
 * `ground: {kind: height_field, z: ...}`; docs/scenes.md "Terrain").
 *
 *  ramp = incline: h = x tan(a) against the plane n . p = 0, n = (-sin a, 0, cos a): the same
 *    rows from another computation of n and the tangents, so RK4 at a fixed step gives the same
 *    trajectory to round-off (1e-12), and dopri5 at rtol 1e-10 within 10 rtol;
 *  bowl = ground sphere: h = R - sqrt(R^2 - x^2 - y^2) against the sphere ground from inside
 *    (both at rtol 1e-12): the period against the closed form 2 pi sqrt(7 (R - r) / 5 g)
 *    (1 + theta0^2 / 16) to 1e-8 (as tests/test_terrain.c) and the two runs' centres within
 *    1e3 rtol R of each other;
 *  gamma of the height-field contact (rolling with no-spin, the wheel knife edge; sphere,
 *    ellipsoid, disk, torus) against central differences of A v + a0 along the motion at
 *    random states (tests/fdcheck.h, FD_TOL), and off by far more without the ground's
 *    curvature term;
 *  the scene's expression layer: h's derivatives from the jets against hand-derived ones
 *    (1e-13), and a ball rolling over Gaussian bumps keeps its energy (within 10 rtol E); the
 *    projected and DAE modes (IDA: the cross-check) follow the minimal mode within 10 rtol m;
 *  a disk (wheel) rolling over a speed bump: energy within 10 rtol E, the velocity constraints
 *    to round-off, the contact gap within the projection tolerance;
 *  errors: a malformed expression (FILE:LINE:COLUMN), a ground curving more sharply than the
 *    ball, h not finite, Newton not converging (derivatives that do not match h), refused
 *    combinations, and no complex-step linearization (named). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "core/core.h"
#include "fdcheck.h"

#define G 9.81
static const double RADIUS = 0.1, MASS = 2.0;

/* ---- height functions (hand-derived derivatives) ---------------------------------------- */

static int ramp_h(double x, double y, double h[6], void *user) {
  double ta = *(const double *)user;
  (void)y;
  h[0] = x * ta, h[1] = ta, h[2] = h[3] = h[4] = h[5] = 0.0;
  return 0;
}

/* The lower half of the sphere of radius R about (0, 0, R). */
static int bowl_h(double x, double y, double h[6], void *user) {
  double R = *(const double *)user, s2 = R * R - x * x - y * y;
  if (!(s2 > 0)) return -1;
  double s = sqrt(s2), s3 = s2 * s;
  h[0] = R - s, h[1] = x / s, h[2] = y / s;
  h[3] = 1 / s + x * x / s3, h[4] = x * y / s3, h[5] = 1 / s + y * y / s3;
  return 0;
}

/* n Gaussian bumps a exp(-((x - cx)^2 + (y - cy)^2) / w), rows (cx, cy, a, w), on a slope. */
typedef struct bumps {
  int n;
  double b[4][4];
  double slope;   /* + slope x */
} bumps;

static int bumps_h(double x, double y, double h[6], void *user) {
  const bumps *B = user;
  memset(h, 0, 6 * sizeof *h);
  h[0] = B->slope * x, h[1] = B->slope;
  for (int k = 0; k < B->n; k++) {
    double dx = x - B->b[k][0], dy = y - B->b[k][1], w = B->b[k][3];
    double g = B->b[k][2] * exp(-(dx * dx + dy * dy) / w);
    h[0] += g, h[1] += -2 * dx / w * g, h[2] += -2 * dy / w * g;
    h[3] += (4 * dx * dx / (w * w) - 2 / w) * g, h[4] += 4 * dx * dy / (w * w) * g;
    h[5] += (4 * dy * dy / (w * w) - 2 / w) * g;
  }
  return 0;
}

/* A ridge across x: a exp(-(x - 1)^2 / w) (a speed bump). */
static int ridge_h(double x, double y, double h[6], void *user) {
  const double *p = user, a = p[0], w = p[1], dx = x - 1.0, g = a * exp(-dx * dx / w);
  (void)y;
  h[0] = g, h[1] = -2 * dx / w * g, h[2] = 0, h[3] = (4 * dx * dx / (w * w) - 2 / w) * g;
  h[4] = h[5] = 0;
  return 0;
}

/* h = 0.1 x^2 with a second derivative that does not match it (a user's slip). */
static int wrong_h(double x, double y, double h[6], void *user) {
  (void)user;
  h[0] = 0.1 * (x * x + y * y), h[1] = 0.2 * x, h[2] = 0.2 * y;
  h[3] = h[5] = 25.0, h[4] = 0.0;
  return 0;
}

/* ---- helpers ------------------------------------------------------------------------------ */

static ap_model *hf_ball(ap_height_fn fn, void *user) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll";
  c.ground.height_fn = fn, c.ground.height_user = user;
  double g[3] = {0, 0, -G};
  return bs_free_ball(AP_SHAPE_SPHERE, RADIUS, MASS, &c, g);
}

static ap_sim *start(const ap_model *m, const ap_sim_def *def, const double *q, const double *v,
                     char *msg, size_t len) {
  ap_sim *s = NULL;
  msg[0] = '\0';
  if (ap_sim_create(m, def, 0.0, q, v, &s, msg, len) != AP_OK) return NULL;
  return s;
}

/* Largest difference of two runs at 20 output times over T (speeds scaled by r). */
static double compare_runs(const ap_model *m1, const ap_model *m2, const ap_sim_def *def,
                           const double *q, const double *v, double T) {
  char msg[1024];
  ap_sim *s1 = start(m1, def, q, v, msg, sizeof msg), *s2 = start(m2, def, q, v, msg, sizeof msg);
  AP_CHECK(s1 && s2);
  if (!s1 || !s2) printf("  %s\n", msg);
  double worst = 0.0;
  for (int k = 1; k <= 20 && s1 && s2; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s1, T * k / 20), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(s2, T * k / 20), AP_OK);
    for (int i = 0; i < 7; i++) worst = fmax(worst, fabs(ap_sim_q(s1)[i] - ap_sim_q(s2)[i]));
    for (int i = 0; i < 6; i++)
      worst = fmax(worst, fabs(ap_sim_v(s1)[i] - ap_sim_v(s2)[i]) * RADIUS);
  }
  ap_sim_free(s1), ap_sim_free(s2);
  return worst;
}

/* ---- (a) ramp = incline ------------------------------------------------------------------- */

static void test_ramp(void) {
  double a = 20 * RS_PI_ / 180, ta = tan(a), n[3] = {-sin(a), 0, cos(a)}, g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll";
  memcpy(c.ground.normal, n, sizeof n);
  ap_model *mi = bs_free_ball(AP_SHAPE_SPHERE, RADIUS, MASS, &c, g), *mh = hf_ball(ramp_h, &ta);
  AP_CHECK(mi && mh);
  if (!mi || !mh) return;
  /* on the ramp at x = 0.3 moving up the slope and across, spinning about n */
  double q[7] = {0.3 - RADIUS * sin(a), 0.1, 0.3 * ta + RADIUS * cos(a), 1, 0, 0, 0};
  double v[6] = {1.2 * cos(a), 0.7, 1.2 * sin(a)}, w[3];
  v3_cross(n, v, w);
  for (int i = 0; i < 3; i++) v[3 + i] = w[i] / RADIUS + 3.0 * n[i];
  ap_sim_def def = ap_sim_def_default();
  def.method = "rk4", def.h_fixed = 1e-3;
  double rk4 = compare_runs(mi, mh, &def, q, v, 2.0);
  def = ap_sim_def_default();
  def.rtol = 1e-10, def.atol = 1e-12;
  double dp = compare_runs(mi, mh, &def, q, v, 2.0);
  printf("  ramp h = x tan(20 deg) vs the incline plane over 2 s: rk4 (h = 1e-3) largest "
         "difference %.2e; dopri5 rtol 1e-10: %.2e\n", rk4, dp);
  AP_CHECK_LE(rk4, 1e-12);
  AP_CHECK_LE(dp, 10 * def.rtol);
  ap_model_free(mi), ap_model_free(mh);
}

/* ---- (b) bowl = ground sphere -------------------------------------------------------------- */

/* Period of the ball released at rest theta0 from the bottom (x crossings), and its centres. */
static double bowl_period(const ap_model *m, double th0, double *xs, int nx) {
  double L = 1.0 - RADIUS, T0 = 2 * RS_PI_ * sqrt(7 * L / (5 * G)), dt = T0 / 400;
  double q[7] = {L * sin(th0), 0, 1 - L * cos(th0), 1, 0, 0, 0}, v[6] = {0}, cross[8];
  ap_sim_def def = ap_sim_def_default();
  def.rtol = 1e-12, def.atol = 1e-14;
  char msg[1024];
  ap_sim *s = start(m, &def, q, v, msg, sizeof msg);
  AP_CHECK(s != NULL);
  if (!s) return printf("  %s\n", msg), NAN;
  double prev = q[0];
  int nc = 0;
  for (int k = 1; k <= nx; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, k * dt), AP_OK);
    const double *x = ap_sim_q(s), *w = ap_sim_v(s);
    xs[3 * (k - 1)] = x[0], xs[3 * (k - 1) + 1] = x[1], xs[3 * (k - 1) + 2] = x[2];
    if ((prev < 0) != (x[0] < 0) && nc < 8) cross[nc++] = k * dt - x[0] / w[0];
    prev = x[0];
  }
  ap_sim_free(s);
  AP_CHECK(nc >= 5);
  return (cross[nc - 1] - cross[0]) / ((nc - 1) / 2.0);
}

static void test_bowl(void) {
  double R = 1.0, th0 = 0.01, L = 1.0 - RADIUS, g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll";
  c.ground.sphere_radius = R, c.ground.sphere_center[2] = R, c.ground.inside = 1;
  ap_model *ms = bs_free_ball(AP_SHAPE_SPHERE, RADIUS, MASS, &c, g), *mh = hf_ball(bowl_h, &R);
  AP_CHECK(ms && mh);
  if (!ms || !mh) return;
  enum { NX = 1300 };
  static double xs[3 * NX], xh[3 * NX];
  double Ts = bowl_period(ms, th0, xs, NX), Th = bowl_period(mh, th0, xh, NX), diff = 0.0;
  double Tref = 2 * RS_PI_ * sqrt(7 * L / (5 * G)) * (1 + th0 * th0 / 16);
  for (int i = 0; i < 3 * NX; i++) diff = fmax(diff, fabs(xs[i] - xh[i]));
  printf("  ball in the bowl h = R - sqrt(R^2 - x^2 - y^2) (R = 1, r = 0.1, theta0 = 0.01, "
         "%.1f s): period %.12g s, closed form %.12g s (relative %.1e); sphere ground %.12g s; "
         "centres differ by %.2e m\n", NX * Tref / 400, Th, Tref, fabs(Th / Tref - 1), Ts, diff);
  AP_CHECK_NEAR(Th, Tref, 1e-8 * Tref);
  AP_CHECK_LE(diff, 1e3 * 1e-12 * R);
  ap_model_free(ms), ap_model_free(mh);
}

/* ---- gamma by finite differences ----------------------------------------------------------- */

static ap_model *shape_on_bumps(int kind, int knife, bumps *B) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "contact", c.no_spin = !knife;
  if (knife) c.kind = AP_CON_KNIFE_EDGE, c.wheel = 1;
  c.ground.height_fn = bumps_h, c.ground.height_user = B;
  return fd_free_shape("shape on bumps", kind, &c);
}

static void test_fd(void) {
  static bumps B = {2, {{0.2, -0.1, 0.3, 0.8}, {-0.5, 0.6, -0.1, 0.5}}, 0.1};
  printf("  height-field contacts, gamma against finite differences along the motion:\n");
  for (int knife = 0; knife < 2; knife++)
    for (int kind = knife ? AP_SHAPE_DISK : AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++) {
      ap_model *m = shape_on_bumps(kind, knife, &B);
      if (!m) continue;
      ap_data *d = NULL;
      AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
      double worst = 0.0, dz = 0.0, bad = 1e300;
      int tries = 0;
      for (int s = 0; s < 6; s++) {
        static meas a, der;
        double q[MAXK], v[MAXK], t, mg[MAXR];
        fd_result r;
        do rand_state(m, q, v, &t), tries++;
        while (measure(m, d, t, q, v, &a) != AP_OK);
        AP_CHECK_EQ_INT(fd_check(m, d, t, q, v, 1e-3, &r, &a, &der), AP_OK);
        AP_CHECK_EQ_INT(measure(m, d, t, q, v, &a), AP_OK);
        for (int i = 0; i < m->b; i++) mg[i] = -a.gamma[i];
        worst = fmax(worst, err_rel(mg, der.c, m->b));
        double gb[MAXR], mb[MAXR];   /* without the ground's curvature (n' = 0) */
        ap_con_rolling_gamma(ap_bm(m), ap_bm_scratch(d), 0, 0, gb);
        for (int i = 0; i < m->b; i++) mb[i] = -gb[i];
        bad = fmin(bad, err_rel(mb, der.c, m->b));
        kwheel W = ap_contact_geom(ap_bm(m), ap_bm_scratch(d), &ap_bm(m)->cons[0]);
        double nv = v3_dot(W.hf + HF_N, der.xm[0]);   /* row .z = n . vP */
        dz = fmax(dz, err_rel(&a.c[m->b - 1], &nv, 1));
      }
      printf("    %-9s %-7s gamma %.1e (without the ground's curvature at least %.1e), row .z "
             "vs n . vP %.1e (%d random states for 6 with a unique contact)\n",
             kind == AP_SHAPE_SPHERE ? "sphere" : kind == AP_SHAPE_ELLIPSOID ? "ellipsoid" :
             kind == AP_SHAPE_DISK ? "disk" : "torus", knife ? "knife" : "rolling", worst, bad,
             dz, tries);
      AP_CHECK_LE(worst, FD_TOL);
      AP_CHECK(bad > 100 * FD_TOL);
      AP_CHECK_LE(dz, FD_TOL);
      ap_data_free(d);
      ap_model_free(m);
    }
}

/* ---- (c) the scene: derivatives from the jets, energy over bumps -------------------------- */

/* The same run in projected and DAE mode (IDA) against the minimal mode's centres xc (30
 * times over T): the largest difference of each. */
static void other_modes(const ap_model *m, const ap_sim_def *def0, const double *q,
                        const double *v, double T, const double *xc, double *diff) {
  for (int mode = 0; mode < 2; mode++) {
    ap_sim_def def = *def0;
    def.mode = mode ? AP_MODE_DAE : AP_MODE_PROJECTED;
    if (mode) def.method = "ida";
    char msg[1024];
    ap_sim *s = start(m, &def, q, v, msg, sizeof msg);
    AP_CHECK(s != NULL);
    if (!s) printf("  %s\n", msg);
    diff[mode] = 0.0;
    for (int k = 1; k <= 30 && s; k++) {
      AP_CHECK_EQ_INT(ap_sim_advance(s, T * k / 30), AP_OK);
      for (int i = 0; i < 3; i++)
        diff[mode] = fmax(diff[mode], fabs(ap_sim_q(s)[i] - xc[3 * (k - 1) + i]));
    }
    ap_sim_free(s);
  }
}

static const char BUMPS_SCENE[] =
    "name: bumps\n"
    "bodies:\n"
    "  ball: {mass: 2.0, shape: {kind: sphere, radius: 0.1}, inertia: uniform}\n"
    "joints:\n"
    "  ball: {kind: free}\n"
    "ground: {kind: height_field, z: \"0.05*exp(-((x-1)^2 + y^2)/0.1) - 0.03*exp(-((x-1.8)^2 +"
    " (y-0.4)^2)/0.15) + 0.04*exp(-((x-2.5)^2 + (y+0.3)^2)/0.08)\"}\n"
    "constraints:\n"
    "  roll: {kind: rolling, body: ball}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  ball: {x: 0, y: 0.1, z: 0.1, vx: 1.2}\n";

static void test_scene_bumps(void) {
  static bumps B = {3, {{1, 0, 0.05, 0.1}, {1.8, 0.4, -0.03, 0.15}, {2.5, -0.3, 0.04, 0.08}}, 0};
  ap_scene *sc = NULL;
  char msg[1024] = "";
  int rc = ap_scene_load_string(BUMPS_SCENE, strlen(BUMPS_SCENE), "bumps.yaml", NULL, 0, &sc,
                                msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)printf("  %s\n", msg);
  const ap_model *m = ap_scene_model(sc);
  ap_ground_motion gm;
  AP_CHECK_EQ_INT(ap_model_constraint_ground(m, 0, &gm), AP_OK);
  AP_CHECK(gm.height_fn != NULL);
  double derr = 0.0;
  for (int k = 0; k < 50 && gm.height_fn; k++) {
    double x = 3 * urand() - 0.2, y = 1.6 * urand() - 0.8, h[6], ref[6];
    AP_CHECK_EQ_INT(gm.height_fn(x, y, h, gm.height_user), 0);
    bumps_h(x, y, ref, &B);
    for (int i = 0; i < 6; i++) derr = fmax(derr, fabs(h[i] - ref[i]) / (1 + fabs(ref[i])));
  }
  double q[7], v[6], E0 = 0, dE = 0, zmin = 1, zmax = 0, T = 3.0, xc[90], diff[2] = {0, 0};
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  ap_sim_def def = ap_sim_def_default();
  def.rtol = 1e-10, def.atol = 1e-12;
  ap_sim *s = start(m, &def, q, v, msg, sizeof msg);
  AP_CHECK(s != NULL);
  AP_CHECK_EQ_INT(ap_scene_energy(sc, 0.0, q, v, &E0), AP_OK);
  for (int k = 1; k <= 300 && s; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, T * k / 300), AP_OK);
    double E = 0;
    AP_CHECK_EQ_INT(ap_scene_energy(sc, ap_sim_time(s), ap_sim_q(s), ap_sim_v(s), &E), AP_OK);
    dE = fmax(dE, fabs(E - E0));
    zmin = fmin(zmin, ap_sim_q(s)[2]), zmax = fmax(zmax, ap_sim_q(s)[2]);
    if (k % 10 == 0) memcpy(xc + 3 * (k / 10 - 1), ap_sim_q(s), 3 * sizeof *xc);
  }
  if (s) other_modes(m, &def, q, v, T, xc, diff);
  ap_sim_stats st;
  if (s) ap_sim_get_stats(s, &st);
  printf("  scene ball over three Gaussian bumps: h's derivatives from the jets vs by hand %.1e; "
         "over %.0f s the centre's height ranged %.4f..%.4f m, energy %.6f J kept to %.2e J "
         "(%ld steps, largest |A v + a0| %.1e)\n", derr, T, zmin, zmax, E0, dE,
         s ? st.steps : 0L, s ? st.max_residual : 0.0);
  AP_CHECK_LE(derr, 1e-13);
  AP_CHECK(zmax - zmin > 0.03);   /* it went over the bumps */
  AP_CHECK_LE(dE, 10 * def.rtol * E0);
  printf("  the same in projected mode and in DAE mode (IDA, the cross-check): centres %.1e and "
         "%.1e m from the minimal mode's\n", diff[0], diff[1]);
  AP_CHECK_LE(diff[0], 10 * def.rtol * 1.0);   /* 10 rtol x the ball's 1 m scale of motion */
  AP_CHECK_LE(diff[1], 10 * def.rtol * 1.0);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* A constraint's own ground replaces the top-level height field (a plane here). */
static void test_scene_own_ground(void) {
  const char *sets[] = {"constraints.roll.ground={normal: [0, 0, 1]}"};
  ap_scene *sc = NULL;
  char msg[1024] = "";
  int rc = ap_scene_load_string(BUMPS_SCENE, strlen(BUMPS_SCENE), "bumps.yaml", sets, 1, &sc,
                                msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_ground_motion gm;
  if (rc == AP_OK) rc = ap_model_constraint_ground(ap_scene_model(sc), 0, &gm);
  AP_CHECK(rc == AP_OK && gm.height_fn == NULL);
  if (rc != AP_OK) printf("  %s\n", msg);
  ap_scene_free(sc);
}

/* ---- (d) a disk (wheel) over a speed bump ------------------------------------------------- */

static void test_disk_bump(void) {
  static double ridge[2] = {0.04, 0.05};
  double r = 0.3, md = 1.0, V = 2.0, g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "wheel";
  c.ground.height_fn = ridge_h, c.ground.height_user = ridge;
  ap_model *m = bs_free_ball(AP_SHAPE_DISK, r, md, &c, g);   /* a uniform disk, free */
  AP_CHECK(m != NULL);
  if (!m) return;
  /* upright, its axis (body z) along -y, rolling along +x: w = (0, V / r, 0) */
  double ax[3] = {1, 0, 0}, q[7] = {0, 0, r}, v[6] = {V, 0, 0, 0, V / r, 0};
  ap_quat_from_axis_angle(ax, RS_PI_ / 2, q + 3);
  ap_sim_def def = ap_sim_def_default();
  def.rtol = 1e-10, def.atol = 1e-12;
  char msg[1024];
  ap_sim *s = start(m, &def, q, v, msg, sizeof msg);
  AP_CHECK(s != NULL);
  if (!s) return (void)printf("  %s\n", msg), ap_model_free(m);
  ap_data *de = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &de), AP_OK);
  double E0 = bs_energy(m, de, ap_sim_q(s), ap_sim_v(s)), dE = 0, zmax = 0, gap = 0;
  for (int k = 1; k <= 100; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.01 * k), AP_OK);
    dE = fmax(dE, fabs(bs_energy(m, de, ap_sim_q(s), ap_sim_v(s)) - E0));
    zmax = fmax(zmax, ap_sim_q(s)[2] - r);
    double phi = 0;
    memcpy(de->q, ap_sim_q(s), 7 * sizeof *de->q), de->t = ap_sim_time(s);
    AP_CHECK_EQ_INT(ap_body_loop_residual(m, de, &phi), AP_OK);
    gap = fmax(gap, phi);
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  printf("  disk (r = 0.3 m) rolling at 2 m/s over a %.0f mm speed bump for 1 s: rose %.4f m; "
         "energy %.6f J kept to %.2e J; largest |A v + a0| %.1e m/s, contact gap %.1e m\n",
         ridge[0] * 1e3, zmax, E0, dE, st.max_residual, gap);
  AP_CHECK(zmax > 0.9 * ridge[0]);
  AP_CHECK_LE(dE, 10 * def.rtol * E0);
  AP_CHECK_LE(st.max_residual, 1e-12 * V);
  AP_CHECK_LE(gap, 1e-12);
  ap_data_free(de);
  ap_sim_free(s);
  ap_model_free(m);
}

/* ---- linearization at the bottom of a dip ------------------------------------------------- */

/* A ball at rest at the bottom of the dip h = (x^2 + y^2) / (2 rho) (radius of curvature rho =
 * 1 m): its centre moves on a surface of radius rho - r, so it rocks at
 * w^2 = 5 g / (7 (rho - r)) (the bowl's pendulum of length 7 (rho - r) / 5). appell linearize's
 * path: no complex step (named), Ridders' differences; eigenvalues within their error bound. */
static const char DIP_SCENE[] =
    "name: dip\n"
    "bodies:\n"
    "  ball: {mass: 2.0, shape: {kind: sphere, radius: 0.1}, inertia: uniform}\n"
    "joints:\n"
    "  ball: {kind: free}\n"
    "ground: {kind: height_field, z: \"0.5*(x^2 + y^2)\"}\n"
    "constraints:\n"
    "  roll: {kind: rolling, body: ball}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  ball: {z: 0.1}\n";

static void test_linearize_dip(void) {
  ap_scene_lin_guess g;
  char msg[1024] = "";
  int rc = ap_scene_lin_guess_load("dip.yaml", DIP_SCENE, strlen(DIP_SCENE), NULL, 0, &g, msg,
                                   sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_lin *L = NULL;
  if (rc == AP_OK) rc = ap_scene_lin_create(&g, NULL, &L);
  if (rc == AP_OK) rc = ap_lin_operating_point(L, NAN);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc == AP_OK) rc = ap_lin_eigen(L, NULL, 0, 1);
  ap_lin_eig e;
  if (rc == AP_OK) rc = ap_lin_get_eigen(L, &e);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) printf("  %s %s\n", msg, L ? ap_lin_message(L) : "");
  double w = sqrt(5 * G / (7 * (1.0 - RADIUS))), worst = 0, bound = 0;
  int pairs = 0;
  for (int i = 0; rc == AP_OK && i < e.n; i++)
    if (e.im[i] > 0) {
      worst = fmax(worst, fabs(e.im[i] - w) + fabs(e.re[i]));
      bound = fmax(bound, e.err[i]);
      pairs++;
    }
  printf("  ball at the bottom of the dip h = (x^2 + y^2) / 2: %d rocking pairs at %.15g rad/s, "
         "closed form %.15g (off %.1e, error bound %.1e; %s)\n", pairs, w + worst, w, worst, bound,
         L ? ap_lin_fallback(L) : "");
  AP_CHECK_EQ_INT(pairs, 2);
  AP_CHECK_LE(worst, fmax(bound, 1e-12 * w));
  AP_CHECK(L && strstr(ap_lin_fallback(L), "height field") != NULL);
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
}

/* ---- (e) errors ------------------------------------------------------------------------------ */

static void expect_load_error(const char *z, const char *want) {
  char text[1024], msg[1024] = "";
  snprintf(text, sizeof text, "name: bad\nbodies:\n  ball: {mass: 1, shape: {kind: sphere, "
           "radius: 0.1}, inertia: uniform}\njoints:\n  ball: {kind: free}\nground: %s\n"
           "constraints:\n  roll: {kind: rolling, body: ball}\n", z);
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, strlen(text), "bad.yaml", NULL, 0, &sc, msg, sizeof msg);
  printf("  refused: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
  AP_CHECK(strstr(msg, want) != NULL);
  AP_CHECK(strstr(msg, "bad.yaml:6:") != NULL);   /* located at the ground line */
  ap_scene_free(sc);
}

/* A run that must stop at its start: sim_create's message. */
static void expect_run_error(ap_height_fn fn, void *user, const double *q, const char *want) {
  ap_model *m = hf_ball(fn, user);
  AP_CHECK(m != NULL);
  if (!m) return;
  double v[6] = {0};
  char msg[1024];
  ap_sim_def def = ap_sim_def_default();
  ap_sim *s = start(m, &def, q, v, msg, sizeof msg);
  AP_CHECK(s == NULL);
  printf("  refused: %s\n", msg);
  AP_CHECK(strstr(msg, want) != NULL && strstr(msg, "constraint 'roll'") != NULL &&
           strstr(msg, "ball") != NULL);
  ap_sim_free(s);
  ap_model_free(m);
}

static int sharp_h(double x, double y, double h[6], void *user) {
  (void)user;
  h[0] = 20 * (x * x + y * y), h[1] = 40 * x, h[2] = 40 * y, h[3] = h[5] = 40, h[4] = 0;
  return 0;
}

static void test_errors(void) {
  expect_load_error("{kind: height_field, z: \"0.05*exp(-(x-1)^2\"}", "z");
  expect_load_error("{kind: height_field, z: \"t*x\"}", "t");
  expect_load_error("{kind: height_field}", "needs z");
  expect_load_error("{kind: height_field, z: \"x\", normal: [0, 0, 1]}", "normal");
  expect_load_error("{z: \"x\"}", "kind: height_field");
  double q[7] = {0, 0, 0.1, 1, 0, 0, 0}, R = 1.0;
  expect_run_error(sharp_h, NULL, q, "curves more sharply");
  double out[7] = {1.5, 0, 0.5, 1, 0, 0, 0};
  expect_run_error(bowl_h, &R, out, "not finite");
  double off[7] = {0.3, 0.2, 0.1, 1, 0, 0, 0};
  expect_run_error(wrong_h, NULL, off, "did not converge");
  /* refused at compile: friction, a plane-contact joint, a moving ground */
  for (int k = 0; k < 3; k++) {
    ap_constraint_def c = ap_constraint_def_default();
    c.name = "roll";
    c.ground.height_fn = bumps_h, c.ground.height_user = NULL;
    if (k == 0) c.mu = 0.5;
    if (k == 2) c.ground.kind = AP_GROUND_TURNTABLE;
    char msg[512];
    int rc = bs_ball_refused(k == 1 ? AP_JOINT_PLANE_CONTACT : AP_JOINT_FREE, RADIUS, MASS, &c,
                             msg, sizeof msg);
    printf("  refused: %s\n", msg);
    AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
    AP_CHECK(strstr(msg, "height") != NULL && strstr(msg, "roll") != NULL);
  }
  /* no complex step: the linearizer says why */
  double ta = 0.1;
  ap_model *m = hf_ball(ramp_h, &ta);
  char why[256] = "";
  AP_CHECK(m && !ap_core_has_cs(m, why, sizeof why));
  printf("  no complex-step linearization: %s\n", why);
  AP_CHECK(strstr(why, "height field") != NULL && strstr(why, "roll") != NULL);
  ap_model_free(m);
}

int main(void) {
  printf("rolling on a height field z = h(x, y):\n");
  test_ramp();
  test_bowl();
  test_fd();
  test_scene_bumps();
  test_scene_own_ground();
  test_disk_bump();
  test_linearize_dip();
  test_errors();
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_heightfield");
}
