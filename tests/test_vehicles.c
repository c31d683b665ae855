/* Vehicles built from bodies (docs/vehicles.md): the example scenes against closed forms.
 *
 *  diff_drive         wheel rates held at w_l, w_r: the axle midpoint on the circle of radius
 *                     R = (b/2)(w_r + w_l)/(w_r - w_l) at speed r (w_r + w_l)/2, 60 s
 *  diff_drive_caster  the same circle; the caster settles where its contact point W and swivel
 *                     point P satisfy |W - C| = sqrt(|P - C|^2 - d^2) (C the centre, d the
 *                     trail), its wheel turning at Omega |W - C| / r_c
 *  diff_drive_loops   plane-contact wheels and an axle of loop closures, coasting with the
 *                     centre of mass on the axle: the same circle at constant rates, 60 s; and
 *                     the first form coasting likewise (same closed form)
 *  car_ackermann      the rear-axle midpoint on the circle of radius L / tan(delta); parallel
 *                     steering refused with the contradicting row named
 *  sleigh_wheel       the Chaplygin sleigh's closed form (docs/references.md §2), m = I = a = 1
 *  skate_wheel        the knife edge on an incline's closed form (§1)
 * Each in minimal and projected mode; the errors are asserted against bounds that follow from
 * rtol (stated with each check), and the step counts are printed. `test_vehicles dae` runs the
 * robots in DAE mode (registered as vehicles_dae), where redundant rows are dropped too. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <appell/appell.h>

#include "check.h"
#include "refsys.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

typedef struct run_out {
  double err;            /* largest error over the outputs (as the check function defines it) */
  double cpu;            /* CPU seconds of the run */
  double max_residual;   /* largest |A v + a0| at step ends */
  ap_sim_stats st;
  double q[64], v[64];   /* the state at the end */
  int rc;
  char msg[1024];
} run_out;

/* Error of the state at t against the closed form (user: the case's parameters). */
typedef double (*err_fn)(const ap_model *m, double t, const double *q, const double *v,
                         void *user);

static ap_scene *load(const char *name, const char *const *sets, int nsets, char *msg,
                      size_t len) {
  char file[1200];
  ap_scene *sc = NULL;
  snprintf(file, sizeof file, "%s/examples/scenes/%s", AP_SRCDIR, name);
  if (ap_scene_load(file, sets, nsets, &sc, msg, len) != AP_OK) return NULL;
  return sc;
}

/* Run a loaded scene in `mode` to t_end, checking at every output interval. */
static void run_loaded(ap_scene *sc, ap_mode mode, double t_end, err_fn f, void *user,
                       run_out *out) {
  const ap_model *m = ap_scene_model(sc);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.mode = mode;
  double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
  ap_sim *sim = NULL;
  memset(out, 0, sizeof *out);
  out->rc = ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, out->msg, sizeof out->msg);
  clock_t c0 = clock();
  if (out->rc == AP_OK)
    out->rc = ap_sim_create(m, &run.sim, run.t0, x, x + ap_model_n(m), &sim, out->msg,
                            sizeof out->msg);
  int nout = (int)lround((t_end - run.t0) / run.interval);
  for (int i = 1; out->rc == AP_OK && i <= nout; i++) {
    double t = i == nout ? t_end : run.t0 + i * run.interval;
    out->rc = ap_sim_advance(sim, t);
    if (out->rc != AP_OK) {
      snprintf(out->msg, sizeof out->msg, "%s", ap_sim_message(sim));
      break;
    }
    double e = f(m, t, ap_sim_q(sim), ap_sim_v(sim), user);
    out->err = fmax(out->err, e);
  }
  out->cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
  if (sim) ap_sim_get_stats(sim, &out->st), out->max_residual = out->st.max_residual;
  if (sim && ap_model_n(m) <= 64 && ap_model_k(m) <= 64) {
    memcpy(out->q, ap_sim_q(sim), sizeof(double) * (size_t)ap_model_n(m));
    memcpy(out->v, ap_sim_v(sim), sizeof(double) * (size_t)ap_model_k(m));
  }
  ap_sim_free(sim);
  free(x);
}

static void run_scene(const char *name, const char *const *sets, int nsets, ap_mode mode,
                      double t_end, err_fn f, void *user, run_out *out) {
  char msg[1024] = "";
  ap_scene *sc = load(name, sets, nsets, msg, sizeof msg);
  if (!sc) {
    memset(out, 0, sizeof *out);
    out->rc = AP_ERR_ARG;
    snprintf(out->msg, sizeof out->msg, "%s", msg);
    return;
  }
  run_loaded(sc, mode, t_end, f, user, out);
  ap_scene_free(sc);
}

static const char *mode_name(ap_mode mode) {
  return mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_PROJECTED ? "projected" : "dae";
}

static void report(const char *label, ap_mode mode, const run_out *o, double tol) {
  printf("  %-18s %-9s error %.2e (bound %.0e)  steps %6ld  evals %7ld  max|Av+a0| %.1e  "
         "cpu %.2f s\n", label, mode_name(mode), o->err, tol, o->st.steps, o->st.rhs_evals,
         o->max_residual, o->cpu);
  if (o->rc != AP_OK) fprintf(stderr, "  %s %s: %s\n", label, mode_name(mode), o->msg);
  AP_CHECK_EQ_INT(o->rc, AP_OK);
  AP_CHECK_LE(o->err, tol);
}

/* ---- the differential-drive robot: a circle ------------------------------------------------ */

typedef struct circle {
  double R, Omega;       /* radius of the axle midpoint's circle, turn rate */
  int ix, iy, ih;        /* coordinates of the chassis: x, y, heading */
} circle;

static void circle_bind(circle *c, const ap_model *m) {
  c->ix = ap_model_find_coord(m, "chassis.x");
  c->iy = ap_model_find_coord(m, "chassis.y");
  c->ih = ap_model_find_coord(m, "chassis.heading");
  AP_CHECK(c->ix >= 0 && c->iy >= 0 && c->ih >= 0);
}

/* Starting at the origin heading along x and turning left: x = R sin(Omega t),
 * y = R (1 - cos(Omega t)), heading Omega t. */
static double circle_err(const ap_model *m, double t, const double *q, const double *v,
                         void *user) {
  circle *c = user;
  (void)v;
  if (c->ix < 0) circle_bind(c, m);
  double th = c->Omega * t;
  return fmax(fmax(fabs(q[c->ix] - c->R * sin(th)), fabs(q[c->iy] - c->R * (1 - cos(th)))),
              fabs(q[c->ih] - th));
}

/* w_l = 8, w_r = 12 rad/s, r = 0.1 m, b = 0.5 m: R = 1.25 m, speed 1 m/s, Omega = 0.8 rad/s. */
static circle robot_circle(void) {
  double wl = 8, wr = 12, r = 0.1, b = 0.5;
  circle c = {0.5 * b * (wr + wl) / (wr - wl), r * (wr - wl) / b, -1, -1, -1};
  AP_CHECK_NEAR(c.R * c.Omega, r * (wr + wl) / 2, 1e-15);   /* speed */
  return c;
}

/* The bound: the heading is the integral of the turn rate, and positions follow it, so the
 * error grows like rtol times the distance travelled (60 m at 1 m/s): one rtol per metre. */
static void test_diff_drive(void) {
  printf("differential-drive robot (rtol 1e-10, 60 s):\n");
  for (int mode = 0; mode < 2; mode++) {
    circle c = robot_circle();
    run_out o;
    run_scene("diff_drive.yaml", NULL, 0, (ap_mode)mode, 60.0, circle_err, &c, &o);
    report("held rates", (ap_mode)mode, &o, 1e-10 * 60);
  }
}

/* The caster: swivel point P 0.3 m behind the axle midpoint, trail d = 0.04 m, wheel radius
 * r_c = 0.05 m. In the chassis frame the centre of the turn is C = (0, R). At the steady state
 * the fork's forward direction e makes (P - C) . e = d, so the contact point W = P - d e has
 * W - C perpendicular to e: e = (d/rho) u + sqrt(1 - d^2/rho^2) (e_z x u), u = (P - C)/rho; the
 * fork angle is atan2(e_y, e_x) and the caster wheel turns at Omega |W - C| / r_c. It settles
 * within a few d / v = 0.04 s; after 60 s it is there to round-off. */
static void test_caster(void) {
  printf("differential-drive robot with a caster (rtol 1e-10, 60 s):\n");
  const double px = -0.3, d = 0.04, rc = 0.05;
  for (int mode = 0; mode < 2; mode++) {
    circle c = robot_circle();
    char msg[1024];
    ap_scene *sc = load("diff_drive_caster.yaml", NULL, 0, msg, sizeof msg);
    AP_CHECK(sc != NULL);
    if (!sc) return;
    const ap_model *m = ap_scene_model(sc);
    run_out o;
    run_loaded(sc, (ap_mode)mode, 60.0, circle_err, &c, &o);
    report("caster", (ap_mode)mode, &o, 1e-10 * 60);
    double ux = px - 0.0, uy = 0.0 - c.R, rho = hypot(ux, uy);
    ux /= rho, uy /= rho;
    double s = sqrt(1 - d * d / (rho * rho));
    double ex = d / rho * ux - s * uy, ey = d / rho * uy + s * ux;
    double psi = atan2(ey, ex), wc = c.Omega * sqrt(rho * rho - d * d) / rc;
    double psi_sim = o.q[ap_model_find_coord(m, "fork.angle")];
    double wc_sim = o.v[ap_model_find_speed(m, "caster.angle_dot")];
    printf("    fork angle %.15f (closed form %.15f), caster rate %.12f (%.12f)\n", psi_sim,
           psi, wc_sim, wc);
    AP_CHECK_NEAR(psi_sim, psi, 1e-10);
    AP_CHECK_NEAR(wc_sim, wc, 1e-10 * wc);
    ap_scene_free(sc);
  }
}

/* The first form coasting: diff_drive.yaml without the held rates, the chassis centre of mass
 * on the axle, started at 8 and 12 rad/s. */
static const char robot_coasting[] =
    "name: diff_drive_coasting\n"
    "bodies:\n"
    "  chassis: {mass: 10.0, inertia: [0.3, 0.5, 0.6]}\n"
    "  wheel_l: {mass: 0.5, shape: {kind: disk, radius: 0.1}, inertia: uniform}\n"
    "  wheel_r: {mass: 0.5, shape: {kind: disk, radius: 0.1}, inertia: uniform}\n"
    "joints:\n"
    "  chassis: {kind: planar, parent_frame: {pos: [0, 0, 0.1]}}\n"
    "  wheel_l: {kind: revolute, parent: chassis,\n"
    "            parent_frame: {pos: [0, 0.25, 0], axis: x, angle: -90*deg}}\n"
    "  wheel_r: {kind: revolute, parent: chassis,\n"
    "            parent_frame: {pos: [0, -0.25, 0], axis: x, angle: -90*deg}}\n"
    "constraints:\n"
    "  roll_l: {kind: rolling, body: wheel_l}\n"
    "  roll_r: {kind: rolling, body: wheel_r}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  wheel_l: {rate: 8.0}\n"
    "  wheel_r: {rate: 12.0}\n"
    "simulation: {rtol: 1e-10, atol: 1e-12, t_end: 60}\n"
    "output: {interval: 0.05}\n";

/* Coasting with the centre of mass on the axle is a Chaplygin sleigh with a = 0: speed and turn
 * rate stay constant, so both forms run on the robot's circle. With revolute wheels the state
 * is the chassis pose and two wheel angles, integrated almost exactly: rtol per metre
 * travelled, as above. With plane-contact wheels the state also holds the wheels' quaternions,
 * spinning through 480 and 720 rad; their integration error feeds the turn rate, which nothing
 * restores (coasting is neutrally stable), so the heading error accumulates: measured at 60 s
 * 370, 260, 120 rtol (minimal) and 1200, 1100, 1100 rtol (projected) at rtol 1e-8, 1e-9, 1e-10.
 * Bound 1e4 rtol. */
static void test_coasting(void) {
  printf("differential-drive robot coasting, both forms (rtol 1e-10, 60 s):\n");
  for (int mode = 0; mode < 2; mode++) {
    circle c = robot_circle();
    run_out o;
    char msg[1024];
    ap_scene *sc = NULL;
    int rc = ap_scene_load_string(robot_coasting, sizeof robot_coasting - 1, "coasting", NULL, 0,
                                  &sc, msg, sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) {
      fprintf(stderr, "%s\n", msg);
      return;
    }
    run_loaded(sc, (ap_mode)mode, 60.0, circle_err, &c, &o);
    report("revolute wheels", (ap_mode)mode, &o, 1e-10 * 60);
    ap_scene_free(sc);
    c = robot_circle();
    run_scene("diff_drive_loops.yaml", NULL, 0, (ap_mode)mode, 60.0, circle_err, &c, &o);
    report("axle of loops", (ap_mode)mode, &o, 1e4 * 1e-10);
    /* The rank kept from ap_partition: deciding it again at every trial state (where the axle's
     * redundant row looks independent) took 200296 steps in projected mode, 17 times more. */
    AP_CHECK(o.st.steps < 30000);
  }
}

/* ---- the car: a circle of radius L / tan(delta) ------------------------------------------ */

/* L = 1.2 m, delta = 0.3 rad, v = 2 m/s: 20 s is 40 m, 1.6 turns. Bound: rtol per metre. */
static void test_car(void) {
  printf("car with Ackermann steering (rtol 1e-10, 20 s):\n");
  for (int mode = 0; mode < 2; mode++) {
    circle c = {1.2 / tan(0.3), 2.0 * tan(0.3) / 1.2, -1, -1, -1};
    run_out o;
    run_scene("car_ackermann.yaml", NULL, 0, (ap_mode)mode, 20.0, circle_err, &c, &o);
    report("Ackermann", (ap_mode)mode, &o, 1e-10 * 40);
  }
  /* Parallel steering: the front wheels' axles no longer meet the rear axle's line in one
   * point, so only rest satisfies every wheel, and the held rear rates contradict it. */
  const char *set[] = {"joints.steer_r.drive.angle=0.3", "joints.steer_l.drive.angle=0.3"};
  circle c = {1.2 / tan(0.3), 2.0 * tan(0.3) / 1.2, -1, -1, -1};
  run_out o;
  run_scene("car_ackermann.yaml", set, 2, AP_MODE_MINIMAL, 1.0, circle_err, &c, &o);
  printf("  parallel steering: %s\n", o.msg);
  AP_CHECK(o.rc != AP_OK);
  AP_CHECK(strstr(o.msg, "contradict") && strstr(o.msg, "inconsistent") &&
           strstr(o.msg, "'roll_f"));
}

/* ---- the sleigh and the skate on a knife-edge wheel ---------------------------------------- */

typedef struct planar_ref {
  rs_sleigh sleigh;
  rs_knife knife;
  int skate;
  double q0[3], v0[3];
  int ix, iy, ih;
} planar_ref;

static double planar_err(const ap_model *m, double t, const double *q, const double *v,
                         void *user) {
  planar_ref *p = user;
  double qe[3], ve[3];
  (void)v;
  if (p->ix < 0) {
    const char *b = p->skate ? "skate" : "sleigh";
    char nm[64];
    snprintf(nm, sizeof nm, "%s.x", b), p->ix = ap_model_find_coord(m, nm);
    snprintf(nm, sizeof nm, "%s.y", b), p->iy = ap_model_find_coord(m, nm);
    snprintf(nm, sizeof nm, "%s.heading", b), p->ih = ap_model_find_coord(m, nm);
  }
  if (p->skate) rs_knife_exact(&p->knife, p->q0, p->v0, t, qe, ve, NULL);
  else rs_sleigh_exact(&p->sleigh, p->q0, p->v0, t, qe, ve);
  return fmax(fmax(fabs(q[p->ix] - qe[0]), fabs(q[p->iy] - qe[1])), fabs(q[p->ih] - qe[2]));
}

/* The wheel's spin does not couple to the body (an axisymmetric wheel with its centre of mass
 * on the axle, whose roll the planar joint carries); the body with the wheel is the reference
 * system with the combined mass m', centre of mass a' and inertia: the scenes choose the body
 * so that these are the existing examples' (sleigh m = I = a = 1; skate m = 1, J = 0.1).
 * Bound 1e-10, as the issue asks, at rtol 1e-11 (the sleigh scene's own; the skate's 1e-10
 * gives 1.4e-10 in minimal mode, as skate_incline.yaml does). */
static void test_knife_wheels(void) {
  printf("sleigh and skate on a knife-edge wheel vs the closed forms:\n");
  for (int mode = 0; mode < 2; mode++) {
    planar_ref p = {{1, 1, 1}, {1, 0.1, 9.81, 0}, 0, {0}, {0}, -1, -1, -1};
    run_out o;
    rs_sleigh_initial(0, 0, RS_PI, 0.1, 0.2, p.q0, p.v0);
    run_scene("sleigh_wheel.yaml", NULL, 0, (ap_mode)mode, 15.0, planar_err, &p, &o);
    report("sleigh wheel", (ap_mode)mode, &o, 1e-10);
    planar_ref k = {{0}, {1.0, 0.1, 9.81, RS_PI / 6}, 1, {0}, {0}, -1, -1, -1};
    rs_knife_initial(0, 0, 0, 1.0, 2.0, k.q0, k.v0);
    const char *tight[] = {"simulation.rtol=1e-11", "simulation.atol=1e-13"};
    run_scene("skate_wheel.yaml", tight, 2, (ap_mode)mode, 10.0, planar_err, &k, &o);
    report("skate wheel", (ap_mode)mode, &o, 1e-10);
  }
}

/* ---- DAE mode ---------------------------------------------------------------------------- */

/* The robots in DAE mode, 60 s: every one has redundant rows (the contact rows .z vanish on the
 * planar chassis; the second wheel's sideways row repeats the first's; on the axle of loops one
 * row is redundant only where the loops close), dropped as the Appell modes drop them. Before
 * issue 11 each failed at t = 0; then the axle of loops stopped at t = 17.66 s (IDA's Newton
 * iteration, multipliers weighed by a stale step size). Bound: one rtol per metre travelled,
 * as for the first form in minimal and projected mode (IDA runs at a tenth of rtol; measured
 * 4.0e-10 to 6.7e-10, 6 to 15 times below). */
static void test_dae(void) {
  printf("the robots in DAE mode (rtol 1e-10, 60 s):\n");
  circle c = robot_circle();
  run_out o;
  run_scene("diff_drive.yaml", NULL, 0, AP_MODE_DAE, 60.0, circle_err, &c, &o);
  report("held rates", AP_MODE_DAE, &o, 60 * 1e-10);
  c = robot_circle();
  run_scene("diff_drive_caster.yaml", NULL, 0, AP_MODE_DAE, 60.0, circle_err, &c, &o);
  report("caster", AP_MODE_DAE, &o, 60 * 1e-10);
  c = robot_circle();
  run_scene("diff_drive_loops.yaml", NULL, 0, AP_MODE_DAE, 60.0, circle_err, &c, &o);
  report("axle of loops", AP_MODE_DAE, &o, 60 * 1e-10);
  c = (circle){1.2 / tan(0.3), 2.0 * tan(0.3) / 1.2, -1, -1, -1};
  run_scene("car_ackermann.yaml", NULL, 0, AP_MODE_DAE, 20.0, circle_err, &c, &o);
  report("car", AP_MODE_DAE, &o, 40 * 1e-10);
}

static double no_err(const ap_model *m, double t, const double *q, const double *v, void *u) {
  (void)m, (void)t, (void)q, (void)v, (void)u;
  return 0.0;
}

/* The bicycle (10 s at 4.6 m/s) at rtol 1e-10 and atol 1e-14, below the round-off of its
 * speeds for IDA (which runs at a tenth: before the floor on atol, IDA's Newton iteration
 * stopped at t = 0.44 s), against minimal mode at the same tolerances: the end states within
 * 100 rtol of each other relative to max(1, |q_i|), as tests/test_bicycle.c bounds the ride. */
static void test_dae_bicycle(void) {
  const char *sets[] = {"simulation.rtol=1e-10", "simulation.atol=1e-14"};
  run_out a, o;
  run_scene("bicycle.yaml", sets, 2, AP_MODE_MINIMAL, 10.0, no_err, NULL, &a);
  run_scene("bicycle.yaml", sets, 2, AP_MODE_DAE, 10.0, no_err, NULL, &o);
  char msg[1024] = "";
  ap_scene *sc = load("bicycle.yaml", sets, 2, msg, sizeof msg);
  AP_CHECK(sc != NULL);
  int n = sc ? ap_model_n(ap_scene_model(sc)) : 0;
  for (int i = 0; i < n && i < 64; i++)
    o.err = fmax(o.err, fabs(o.q[i] - a.q[i]) / fmax(1.0, fabs(a.q[i])));
  ap_scene_free(sc);
  AP_CHECK_EQ_INT(a.rc, AP_OK);
  report("bicycle vs minimal", AP_MODE_DAE, &o, 100 * 1e-10);
}

int main(int argc, char **argv) {
  if (argc > 1 && strcmp(argv[1], "dae") == 0) {
    test_dae();
    test_dae_bicycle();
    return ap_check_finish("test_vehicles dae");
  }
  test_diff_drive();
  test_caster();
  test_coasting();
  test_car();
  test_knife_wheels();
  return ap_check_finish("test_vehicles");
}
