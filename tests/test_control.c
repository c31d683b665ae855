/* Inputs and controllers in the loop (include/appell/control.h) against closed forms.
 *
 * The double integrator m x'' = u (a math-level system, and a body on a prismatic joint from a
 * scene) with a PD controller u_j = -kp x_j - kd v_j sampled every T and held (zero-order
 * hold) has the exact discrete solution
 *
 *     x_{j+1} = x_j + T v_j + T^2 u_j / (2 m),    v_{j+1} = v_j + T u_j / m,
 *
 * which the simulation must reproduce at every instant j T in every mode: the input is
 * piecewise constant, so each interval is a quadratic in t that the steppers follow to their
 * tolerance (rtol 1e-10, states of size 1: 1e-8 allowed; DAE mode's BDF restarts at order 1
 * after each jump, 1e-6 allowed). A constant force F from rest gives x = F t^2 / (2 m).
 * The error paths: unknown names, NaN from the controller, a controller that stops, a bad
 * period, no inputs declared; each message names the input and the time. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#define MASS 2.0
#define KP 4.0
#define KD 1.5
#define PERIOD 0.05

static int di_metric(double t, const double *q, double *g, void *user) {
  (void)t, (void)q, (void)user;
  g[0] = MASS;
  return 0;
}

static ap_model *double_integrator(void) {
  static const char *const coords[] = {"x"}, *const speeds[] = {"x_dot"};
  ap_system_def def = ap_system_def_default();
  def.name = "double_integrator";
  def.n = 1, def.k = 1;
  def.metric = di_metric;
  def.bias_source = AP_BIAS_ZERO;
  def.coord_names = coords, def.speed_names = speeds;
  ap_model *m = NULL;
  char msg[256];
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_OK);
  return m;
}

typedef struct pd {
  int calls;
  double t_err;            /* largest |t - j T| over the calls */
  double t0;
  int mode;                /* 0: PD, 1: NaN, 2: stop */
} pd;

static int pd_fn(double t, const double *q, const double *v, double *u, void *user) {
  pd *c = user;
  c->t_err = fmax(c->t_err, fabs(t - c->t0 - c->calls * PERIOD));
  c->calls++;
  if (c->mode == 1 && t > 0.2) u[0] = NAN;
  else if (c->mode == 2 && t > 0.2) return -7;
  else u[0] = -KP * q[0] - KD * v[0];
  return 0;
}

static ap_sim *make_sim_method(const ap_model *m, ap_mode mode, const char *method, double x0,
                               double v0) {
  ap_sim_def def = ap_sim_def_default();
  def.mode = mode, def.rtol = 1e-10, def.atol = 1e-12;
  if (method) def.method = method;
  ap_sim *s = NULL;
  char msg[256];
  int rc = ap_sim_create(m, &def, 0.0, &x0, &v0, &s, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  return s;
}

static ap_sim *make_sim(const ap_model *m, ap_mode mode, double x0, double v0) {
  return make_sim_method(m, mode, NULL, x0, v0);
}

/* The simulation against the discrete solution at every instant up to t = 3. */
static void check_zoh(ap_sim *s, double tol, const char *what) {
  double x = ap_sim_q(s)[0], v = ap_sim_v(s)[0], err = 0.0;
  pd c = {0, 0.0, ap_sim_time(s), 0};
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, pd_fn, PERIOD, &c), AP_OK);
  for (int j = 1; j <= 60; j++) {
    double u = -KP * x - KD * v;
    x += PERIOD * v + PERIOD * PERIOD * u / (2 * MASS);
    v += PERIOD * u / MASS;
    int rc = ap_sim_advance(s, c.t0 + j * PERIOD);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) return (void)fprintf(stderr, "%s: %s\n", what, ap_sim_message(s));
    err = fmax(err, fmax(fabs(ap_sim_q(s)[0] - x), fabs(ap_sim_v(s)[0] - v)));
  }
  printf("%-28s ZOH PD: largest error %.3g over 60 periods, %d calls\n", what, err, c.calls);
  AP_CHECK_LE(err, tol);
  AP_CHECK_EQ_INT(c.calls, 61);   /* t = 0, T, ..., 60 T (the last when the next advance runs) */
  AP_CHECK_LE(c.t_err, 1e-12);
}

static void test_math_level(void) {
  ap_model *m = double_integrator();
  const char *const in[] = {"x_dot", NULL};
  const ap_mode modes[] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  const char *names[] = {"math-level, minimal", "math-level, projected", "math-level, DAE"};
  for (int i = 0; i < 3; i++) {
    ap_sim *s = make_sim(m, modes[i], 1.0, 0.0);
    AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
    check_zoh(s, modes[i] == AP_MODE_DAE ? 1e-6 : 1e-8, names[i]);
    ap_sim_free(s);
  }
  /* Every kind of stepper continuation: our FSAL pair (dop853), ERKStep without and with FSAL
   * (verner6, dopri5 above), CVODE's multistep methods (reset at each jump: restarted at order
   * 1, their error follows rtol, 1e-6 allowed). */
  const char *methods[] = {"dop853", "verner6", "adams", "bdf"};
  for (int i = 0; i < 4; i++) {
    char what[64];
    snprintf(what, sizeof what, "math-level, minimal, %s", methods[i]);
    ap_sim *s = make_sim_method(m, AP_MODE_MINIMAL, methods[i], 1.0, 0.0);
    AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
    check_zoh(s, i < 2 ? 1e-8 : 1e-6, what);
    ap_sim_free(s);
  }
  /* A constant force from rest, then none: x = F t^2 / (2 m), then uniform motion. */
  ap_sim *s = make_sim(m, AP_MODE_MINIMAL, 0.0, 0.0);
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_input_count(s), 1);
  AP_CHECK(strcmp(ap_sim_input_name(s, 0), "x_dot") == 0);
  AP_CHECK_EQ_INT(ap_sim_find_input(s, "x_dot"), 0);
  AP_CHECK_EQ_INT(ap_sim_set_input(s, "x_dot", 3.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 1.0), AP_OK);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 3.0 / (2 * MASS), 1e-10);
  AP_CHECK_NEAR(ap_sim_data(s)->vdot[0], 3.0 / MASS, 1e-14);   /* the data has the input */
  double zero = 0.0;
  AP_CHECK_EQ_INT(ap_sim_set_inputs(s, &zero), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2.0), AP_OK);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 3.0 / (2 * MASS) + 3.0 / MASS, 1e-10);
  AP_CHECK_NEAR(ap_sim_inputs(s)[0], 0.0, 0.0);
  ap_sim_free(s);
  ap_model_free(m);
}

static int x_fn(double t, const double *q, const double *v, const ap_data *d, void *user,
                double *f) {
  (void)t, (void)v, (void)d, (void)user;
  *f = q[0];
  return 0;
}

/* A stop event between two instants (x crossing 0) and a controller: the event time is the
 * root of the interval's quadratic x_j + v_j tau + u_j tau^2 / (2 m), and after the stop the
 * instants go on at j T with the values of the recursion. */
static void test_with_event(void) {
  ap_model *m = double_integrator();
  const char *const in[] = {"x_dot", NULL};
  ap_sim *s = make_sim(m, AP_MODE_MINIMAL, 1.0, 0.0);
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
  ap_event_def ev = ap_event_def_default();
  ev.name = "x0", ev.fn = x_fn;
  AP_CHECK_EQ_INT(ap_sim_add_event(s, &ev), AP_OK);
  pd c = {0, 0.0, 0.0, 0};
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, pd_fn, PERIOD, &c), AP_OK);
  double x = 1.0, v = 0.0, t_root = NAN;
  int j = 0;
  for (; j < 60 && isnan(t_root); j++) {   /* the interval where x changes sign */
    double u = -KP * x - KD * v, x1 = x + PERIOD * v + PERIOD * PERIOD * u / (2 * MASS);
    if (x1 < 0) {
      double a = u / (2 * MASS), disc = v * v - 4 * a * x;
      double tau = a != 0 ? (-v - sqrt(disc)) / (2 * a) : -x / v;
      if (!(tau > 0 && tau < PERIOD)) tau = (-v + sqrt(disc)) / (2 * a);
      t_root = j * PERIOD + tau;
    }
    x = x1, v += PERIOD * u / MASS;
  }
  AP_CHECK_EQ_INT(ap_sim_advance(s, 3.0), AP_STOPPED);
  printf("stop event x = 0 at t = %.15g, the quadratic's root %.15g\n", ap_sim_time(s), t_root);
  AP_CHECK_NEAR(ap_sim_time(s), t_root, 1e-9);
  AP_CHECK_EQ_INT(c.calls, j);   /* the instants before the event, none since */
  for (; j <= 40; j++) {        /* and on, at the instants j T */
    AP_CHECK_EQ_INT(ap_sim_advance(s, j * PERIOD), AP_OK);
    if (j > 0) {
      AP_CHECK_NEAR(ap_sim_q(s)[0], x, 1e-8);
      double u = -KP * x - KD * v;
      x += PERIOD * v + PERIOD * PERIOD * u / (2 * MASS), v += PERIOD * u / MASS;
    }
  }
  AP_CHECK_LE(c.t_err, 1e-12);
  ap_sim_free(s);
  ap_model_free(m);
}

/* Each failure is refused with its status and a message containing every one of words. */
static void expect(int rc, int status, const ap_sim *s, const char *w1, const char *w2) {
  AP_CHECK_EQ_INT(rc, status);
  const char *msg = ap_sim_message(s);
  AP_CHECK(strstr(msg, w1) != NULL);
  AP_CHECK(!w2 || strstr(msg, w2) != NULL);
  printf("  refused (%d): %s\n", rc, msg);
}

static void test_errors(void) {
  ap_model *m = double_integrator();
  ap_sim *s = make_sim(m, AP_MODE_MINIMAL, 1.0, 0.0);
  pd c = {0, 0.0, 0.0, 1};
  expect(ap_sim_set_controller(s, pd_fn, PERIOD, &c), AP_ERR_ARG, s, "no inputs", NULL);
  expect(ap_sim_set_input(s, "x_dot", 1.0), AP_ERR_ARG, s, "no inputs", NULL);
  const char *const bad[] = {"x_dto", NULL}, *const twice[] = {"x_dot", "x_dot", NULL};
  expect(ap_sim_declare_inputs(s, bad), AP_ERR_ARG, s, "'x_dto' is not a speed", "x_dot");
  expect(ap_sim_declare_inputs(s, twice), AP_ERR_ARG, s, "twice", NULL);
  const char *const in[] = {"x_dot", NULL};
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
  expect(ap_sim_set_input(s, "x_do", 1.0), AP_ERR_ARG, s, "no input 'x_do'", "x_dot");
  expect(ap_sim_set_input(s, "x_dot", NAN), AP_ERR_NAN, s, "'x_dot'", "t = 0");
  expect(ap_sim_set_controller(s, pd_fn, 0.0, &c), AP_ERR_ARG, s, "period", NULL);
  expect(ap_sim_set_controller(s, pd_fn, INFINITY, &c), AP_ERR_ARG, s, "period", NULL);
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, pd_fn, PERIOD, &c), AP_OK);
  expect(ap_sim_advance(s, 1.0), AP_ERR_NAN, s, "input 'x_dot' = nan", "t = 0.25");
  AP_CHECK_NEAR(ap_sim_time(s), 0.25, 1e-12);   /* stopped where the controller failed */
  ap_sim_free(s);
  s = make_sim(m, AP_MODE_PROJECTED, 1.0, 0.0);
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(s, in), AP_OK);
  c = (pd){0, 0.0, 0.0, 2};
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, pd_fn, PERIOD, &c), AP_OK);
  expect(ap_sim_advance(s, 1.0), AP_ERR_CALLBACK, s, "returned -7", "t = 0.25");
  ap_sim_free(s);
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(NULL, in), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_sim_input_count(NULL), 0);
  AP_CHECK(ap_sim_inputs(NULL) == NULL && ap_sim_input_name(NULL, 0) == NULL);
  ap_model_free(m);
}

/* The same on a body: a cart of mass 2 on a prismatic joint, from a scene with inputs:. The
 * linearizer's default inputs are the scene's: B = [0; 1/m]. */
static const char *cart_scene =
    "name: cart\n"
    "bodies: {cart: {mass: 2, inertia: [0.1, 0.1, 0.1]}}\n"
    "joints: {cart: {kind: prismatic, axis: x}}\n"
    "initial: {cart: {position: 1}}\n"
    "inputs: [%s]\n"
    "linearize: {about: equilibrium}\n";

static void test_scene(void) {
  char text[1024], msg[512];
  snprintf(text, sizeof text, cart_scene, "cart.pos_dot");
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, strlen(text), "cart.yaml", NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)fprintf(stderr, "%s\n", msg);
  const ap_model *m = ap_scene_model(sc);
  double q[1], v[1];
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  {
    ap_scene_run run;
    ap_scene_get_run(sc, &run);
    run.sim.rtol = 1e-10, run.sim.atol = 1e-12;
    ap_sim *s = NULL;
    AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, 0.0, q, v, &s, msg, sizeof msg), AP_OK);
    AP_CHECK_EQ_INT(ap_scene_add_inputs(sc, s, msg, sizeof msg), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_input_count(s), 1);
    check_zoh(s, 1e-8, "scene cart, minimal");
    ap_sim_free(s);
  }
  ap_scene_lin lin;
  AP_CHECK_EQ_INT(ap_scene_get_linearize(sc, &lin, msg, sizeof msg), AP_OK);
  AP_CHECK(lin.inputs && lin.inputs[0] && strcmp(lin.inputs[0], "cart.pos_dot") == 0);
  ap_scene_lin_free(&lin);
  AP_CHECK_EQ_INT(ap_scene_add_inputs(NULL, NULL, msg, sizeof msg), AP_ERR_ARG);
  ap_scene_free(sc);
  /* A name that is not a speed: located, with the closest one. */
  snprintf(text, sizeof text, cart_scene, "cart.pos_dto");
  rc = ap_scene_load_string(text, strlen(text), "cart.yaml", NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
  AP_CHECK(strstr(msg, "cart.yaml:5:") != NULL && strstr(msg, "cart.pos_dot") != NULL);
  printf("  refused: %s\n", msg);
}

int main(void) {
  test_math_level();
  test_with_event();
  test_errors();
  test_scene();
  return ap_check_finish("control");
}
