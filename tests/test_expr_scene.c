/* Scene expressions in simulations (docs/scenes.md "Expressions", "Kinks").
 *
 * 1. tests/scenes/kinks_fn.yaml: the kinks of max, clamp, sign and floor in joint forces are
 *    events hit to round-off: the run matches the closed-form double integrals of the
 *    piecewise forces to 1e-10 at rtol 1e-12, with every kink recorded at its exact time.
 * 2. Body quantities (ap_body_quantity, tests/scenes/act_body.yaml) at states along a run:
 *    Rz(yaw) Ry(pitch) Rx(roll) and Rz(heading) Rx(tilt) Rz(spin) rebuild ap_body_get_state's R
 *    to 1e-15; x, y, z is its origin; the angular velocity is its omega; the origin's velocity
 *    equals the central difference of the position along the motion (q +- h v, revolute joints
 *    have q' = v) to the difference's error. (Their partial derivatives: tests/test_lin_cs.c,
 *    complex step against Ridders on act_body.yaml.)
 * 3. Named output channels through the command line: the bicycle's `lean: rear_frame.roll`
 *    equals the roll computed here from the quaternion columns of its free joint (R of the joint
 *    times the child frame's Rx(90 deg)^T) to 1e-12; `appell plot --y lean` accepts the name
 *    and `--y leen` suggests it; the car's `driven` channel gives the Ackermann steer angles and
 *    its `contacts` channel the wheel contact points, under the upright wheels' centres.
 * 4. A lean controller written with atan2 at upright: the benchmark bicycle with a steer torque
 *    T = k1 (2 atan2(qx, qw) - pi/2) + k2 wx (the lean from its free joint's quaternion, and the
 *    roll rate), linearized at 3 m/s upright by `appell linearize` (complex step): its A equals
 *    the uncontrolled bicycle's A plus k1 and k2 times the steer column of the uncontrolled B
 *    in the roll and roll-rate columns, to the 6 digits the command prints.
 * 5. An event on a body quantity: the falling bicycle's `when: rear_frame.roll - 0.5` fires at
 *    the same time as the same roll written from its free joint's quaternion coordinates. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

#define RS_HALF_PI 1.57079632679489661923

/* A simulation of the scene at path from its initial state, with its events; *sc receives the
 * scene. NULL (counted as a failure) when something fails. */
static ap_sim *load_sim(const char *path, ap_scene **sc) {
  char msg[1024];
  ap_sim *s = NULL;
  int rc = ap_scene_load(path, NULL, 0, sc, msg, sizeof msg);
  const ap_model *m = rc == AP_OK ? ap_scene_model(*sc) : NULL;
  double *x = m ? calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof *x) : NULL;
  if (rc == AP_OK && !x) rc = AP_ERR_NOMEM;
  if (rc == AP_OK)
    rc = ap_scene_initial_state(*sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg);
  ap_scene_run run;
  if (rc == AP_OK) {
    ap_scene_get_run(*sc, &run);
    rc = ap_sim_create(m, &run.sim, run.t0, x, x + ap_model_n(m), &s, msg, sizeof msg);
  }
  if (rc == AP_OK) rc = ap_scene_add_events(*sc, s, msg, sizeof msg);
  free(x);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", path, msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) ap_sim_free(s), s = NULL;
  return s;
}

/* ---- 1. kinks of min, max, clamp, sign, floor ------------------------------------------------ */

static double r2(double u) { return u > 0 ? u * u / 2 : 0.0; }
static double r3(double u) { return u > 0 ? u * u * u / 6 : 0.0; }

/* x'' = max(0, t - 1) - 2 clamp(t - 2, 0, 0.5) + sign(t - 3), y'' = floor(t / 1.5), from rest. */
static void kinks_exact(double t, double *x, double *y) {
  *x = r3(t - 1) - 2 * (r3(t - 2) - r3(t - 2.5)) - t * t / 2 + 2 * r2(t - 3);
  *y = r2(t - 1.5) + r2(t - 3) + r2(t - 4.5);
}

static void test_kinks(const char *path) {
  ap_scene *sc = NULL;
  ap_sim *s = load_sim(path, &sc);
  double err = 0.0, x, y;
  for (int i = 1; s && i <= 16; i++) {   /* output times off the kinks */
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.3 * i), AP_OK);
    kinks_exact(0.3 * i, &x, &y);
    err = fmax(err, fmax(fabs(ap_sim_q(s)[0] - x), fabs(ap_sim_q(s)[1] - y)));
  }
  if (s) {
    static const double when[] = {1, 1.5, 2, 2.5, 3, 3, 4.5};
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    printf("kinks of max, clamp, sign, floor: max error %.2e, %ld steps, %ld rejected, "
           "%d events\n", err, st.steps, st.err_fails, ap_sim_event_count(s));
    AP_CHECK_LE(err, 1e-10);
    AP_CHECK_EQ_INT(ap_sim_event_count(s), 7);
    for (int i = 0; i < 7 && i < ap_sim_event_count(s); i++) {
      ap_event_record ev;
      AP_CHECK_EQ_INT(ap_sim_event_get(s, i, &ev), AP_OK);
      AP_CHECK_NEAR(ev.t, when[i], 1e-14);
    }
  }
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* ---- 2. body quantities ------------------------------------------------------------------- */

static void rot(int axis, double a, double *R) {   /* column-major rotation about axis */
  double c = cos(a), s = sin(a);
  int i = (axis + 1) % 3, j = (axis + 2) % 3;
  memset(R, 0, 9 * sizeof *R);
  R[axis + 3 * axis] = 1, R[i + 3 * i] = c, R[j + 3 * j] = c, R[j + 3 * i] = s, R[i + 3 * j] = -s;
}

static void mul(const double *A, const double *B, double *C) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      C[i + 3 * j] = 0;
      for (int k = 0; k < 3; k++) C[i + 3 * j] += A[i + 3 * k] * B[k + 3 * j];
    }
}

/* max |R - Rz(a) R_axis2(b) Rz/x(c)| for the angles (a, b, c) about (axes[0], axes[1], axes[2]). */
static double rebuild(const double *R, const int axes[3], double a, double b, double c) {
  double A[9], B[9], C[9], AB[9], ABC[9], e = 0;
  rot(axes[0], a, A), rot(axes[1], b, B), rot(axes[2], c, C);
  mul(A, B, AB), mul(AB, C, ABC);
  for (int i = 0; i < 9; i++) e = fmax(e, fabs(ABC[i] - R[i]));
  return e;
}

static void qty(const ap_model *m, ap_data *d, int b, double *x) {
  AP_CHECK_EQ_INT(ap_body_eval(m, d), AP_OK);
  for (int i = 0; i < AP_BODY_QTY_COUNT; i++) AP_CHECK_EQ_INT(ap_body_quantity(m, d, b, i, &x[i]), AP_OK);
}

static void test_body_quantities(const char *path) {
  ap_scene *sc = NULL;
  ap_sim *s = load_sim(path, &sc);
  const ap_model *m = sc ? ap_scene_model(sc) : NULL;
  ap_data *d = NULL;
  if (!s || ap_data_create(m, &d) != AP_OK) return ap_sim_free(s), ap_scene_free(sc);
  static const int zyx[3] = {2, 1, 0}, zxz[3] = {2, 0, 2};
  double worst_R = 0, worst_o = 0, worst_v = 0, h = 1e-5;
  int n = ap_model_n(m);
  for (int step = 1; step <= 8; step++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.25 * step), AP_OK);
    for (int b = 0; b < 3; b++) {
      double x[AP_BODY_QTY_COUNT], xp[AP_BODY_QTY_COUNT], xm[AP_BODY_QTY_COUNT];
      ap_body_state st;
      d->t = ap_sim_time(s);
      memcpy(d->q, ap_sim_q(s), sizeof(double) * (size_t)n);
      memcpy(d->v, ap_sim_v(s), sizeof(double) * (size_t)n);
      qty(m, d, b, x);
      AP_CHECK_EQ_INT(ap_body_get_state(m, d, b, &st), AP_OK);
      worst_R = fmax(worst_R, rebuild(st.R, zyx, x[AP_BODY_YAW], x[AP_BODY_PITCH], x[AP_BODY_ROLL]));
      worst_R = fmax(worst_R, rebuild(st.R, zxz, x[AP_BODY_HEADING], x[AP_BODY_TILT], x[AP_BODY_SPIN]));
      for (int i = 0; i < 3; i++) {
        worst_o = fmax(worst_o, fabs(x[AP_BODY_X + i] - st.pos[i]));
        worst_o = fmax(worst_o, fabs(x[AP_BODY_WX + i] - st.omega[i]));
      }
      for (int i = 0; i < n; i++) d->q[i] = ap_sim_q(s)[i] + h * ap_sim_v(s)[i];
      qty(m, d, b, xp);
      for (int i = 0; i < n; i++) d->q[i] = ap_sim_q(s)[i] - h * ap_sim_v(s)[i];
      qty(m, d, b, xm);
      for (int i = 0; i < 3; i++)
        worst_v = fmax(worst_v, fabs((xp[AP_BODY_X + i] - xm[AP_BODY_X + i]) / (2 * h) - x[AP_BODY_VX + i]));
    }
  }
  printf("body quantities: angles rebuild R to %.1e, position and omega %.1e, velocity against "
         "central differences (h = 1e-5) %.1e\n", worst_R, worst_o, worst_v);
  AP_CHECK_LE(worst_R, 1e-15);
  AP_CHECK_LE(worst_o, 0.0);
  AP_CHECK_LE(worst_v, 1e-9);   /* h^2 |x'''| / 6 ~ 1e-10 plus round-off 1e-16 / h */
  ap_data_free(d);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* ---- 3. named channels, driven, wheel contacts --------------------------------------------- */

/* Column index of name in the CSV header line, or -1. */
static int column(const char *header, const char *name) {
  char buf[8192];
  snprintf(buf, sizeof buf, "%s", header);
  int i = 0;
  for (char *tok = strtok(buf, ",\n"); tok; tok = strtok(NULL, ",\n"), i++)
    if (strcmp(tok, name) == 0) return i;
  return -1;
}

/* Rows of a CSV (at most 64 x 128 values), its header into header. */
static int read_csv(const char *path, char *header, size_t len, double rows[64][128]) {
  FILE *f = fopen(path, "r");
  int n = 0;
  if (!f || !fgets(header, (int)len, f)) return f ? fclose(f), 0 : 0;
  char line[8192];
  while (n < 64 && fgets(line, sizeof line, f)) {
    int i = 0;
    for (char *tok = strtok(line, ","); tok && i < 128; tok = strtok(NULL, ",")) rows[n][i++] = atof(tok);
    n++;
  }
  fclose(f);
  return n;
}

static double rows[64][128];

static void test_channels(const char *src) {
  char scene[1200], csv[200], fig[200], header[8192];
  snprintf(scene, sizeof scene, "%s/examples/scenes/bicycle.yaml", src);
  snprintf(csv, sizeof csv, "%s/bicycle.csv", ct_tmp);
  snprintf(fig, sizeof fig, "%s/lean.png", ct_tmp);
  const char *run[] = {ct_bin, "run", scene, "--set", "simulation.t_end=1", "--set",
                       "output.interval=0.05", "--out", csv, NULL};
  AP_CHECK_EQ_INT(ct_run(run), 0);
  int n = read_csv(csv, header, sizeof header, rows), lean = column(header, "lean");
  int qw = column(header, "rear_frame.qw");
  AP_CHECK(n == 21 && lean > 0 && qw > 0);
  double worst = 0, lmax = 0;
  for (int r = 0; r < n && lean > 0 && qw > 0; r++) {
    double q[4] = {rows[r][qw], rows[r][qw + 1], rows[r][qw + 2], rows[r][qw + 3]}, Rj[9], Rc[9], R[9];
    ap_quat_to_matrix(q, Rj);
    rot(0, -RS_HALF_PI, Rc);   /* the child frame's Rx(90 deg), transposed */
    mul(Rj, Rc, R);
    double roll = atan2(R[5], R[8]);
    worst = fmax(worst, fabs(rows[r][lean] - roll)), lmax = fmax(lmax, fabs(roll));
  }
  printf("bicycle lean channel against the roll from the quaternion columns: %.1e (lean up to "
         "%.3f rad)\n", worst, lmax);
  AP_CHECK_LE(worst, 1e-12);
  AP_CHECK(lmax > 0.05);   /* it did lean */
  const char *plot[] = {ct_bin, "plot", csv, "--y", "lean", "-o", fig, NULL};
  int rc = ct_run(plot);
  AP_CHECK(rc == 0 || rc == 1);   /* 1: gnuplot missing */
  if (rc == 0) remove(fig);
  const char *bad[] = {ct_bin, "plot", csv, "--y", "leen", "-o", fig, NULL};
  AP_CHECK_EQ_INT(ct_run(bad), 2);
  AP_CHECK(ct_log_has("did you mean 'lean'?"));
  remove(csv);
  char rec[260];
  snprintf(rec, sizeof rec, "%s.run.json", csv);
  remove(rec);

  /* the car: driven steer angles, wheel contact points under the wheel centres */
  snprintf(scene, sizeof scene, "%s/examples/scenes/car_ackermann.yaml", src);
  const char *car[] = {ct_bin, "run", scene, "--set", "simulation.t_end=1", "--set",
                       "output.channels=[driven, contacts, poses]", "--out", csv, NULL};
  AP_CHECK_EQ_INT(ct_run(car), 0);
  n = read_csv(csv, header, sizeof header, rows);
  int sl = column(header, "steer_l.angle"), sr = column(header, "steer_r.angle");
  int cx = column(header, "front_l.contact.x"), px = column(header, "front_l.pos.x");
  AP_CHECK(n == 21 && sl > 0 && sr > 0 && cx > 0 && px > 0);
  double werr = 0;
  for (int r = 0; r < n && sl > 0 && sr > 0 && cx > 0 && px > 0; r++) {
    AP_CHECK_NEAR(rows[r][sl], atan(1.2 / (1.2 / tan(0.3) - 0.4)), 1e-15);
    AP_CHECK_NEAR(rows[r][sr], atan(1.2 / (1.2 / tan(0.3) + 0.4)), 1e-15);
    werr = fmax(werr, fmax(fabs(rows[r][cx] - rows[r][px]), fabs(rows[r][cx + 1] - rows[r][px + 1])));
  }
  printf("car: wheel contact point under the wheel centre to %.1e m\n", werr);
  AP_CHECK_LE(werr, 1e-12);
  remove(csv);
  remove(rec);
}

/* ---- 4. the atan2 lean controller at upright -------------------------------------------------- */

#define NX 10
/* The rows of A (nx x nx) and of B (nx x 2) printed by appell linearize into file; 0 when
 * both have NX rows. */
static int read_lin(const char *file, double A[NX][NX], double B[NX][2]) {
  FILE *f = fopen(file, "r");
  char line[4096];
  int block = 0, na = 0, nb = 0;
  while (f && fgets(line, sizeof line, f)) {
    if (strncmp(line, "state matrix A", 14) == 0) block = 1;
    else if (strncmp(line, "input matrix B", 14) == 0) block = 2;
    else if (strncmp(line, "  ", 2) != 0 || line[2] == ' ') block = 0;
    else if (block) {
      char *p = line + 2;
      while (*p && *p != ' ') p++;   /* the row's name */
      for (int j = 0; j < (block == 1 ? NX : 2); j++) {
        double x = strtod(p, &p);
        if (block == 1 && na < NX) A[na][j] = x;
        if (block == 2 && nb < NX) B[nb][j] = x;
      }
      block == 1 ? na++ : nb++;
    }
  }
  if (f) fclose(f);
  return na == NX && nb == NX ? 0 : -1;
}

static void test_lean_controller(const char *src) {
  char scene[1200], ctl[200], out[2][200];
  snprintf(scene, sizeof scene, "%s/examples/scenes/bicycle.yaml", src);
  snprintf(ctl, sizeof ctl, "%s/bicycle_ctl.yaml", ct_tmp);
  const double k1 = 100, k2 = 20;
  FILE *in = fopen(scene, "r"), *o = fopen(ctl, "w");
  char line[1024];
  AP_CHECK(in && o);
  while (in && o && fgets(line, sizeof line, in)) {
    fputs(line, o);
    if (strstr(line, "gravity: {kind: gravity"))
      fprintf(o, "  steer: {kind: joint_torque, joint: front_frame, torque: \"%g*(2*atan2("
              "rear_frame.qx, rear_frame.qw) - pi/2) + %g*rear_frame.wx\"}\n", k1, k2);
  }
  if (in) fclose(in);
  if (o) fclose(o);
  static double A[2][NX][NX], B[2][NX][2];
  for (int i = 0; i < 2; i++) {
    snprintf(out[i], sizeof out[i], "%s/lin%d.txt", ct_tmp, i);
    FILE *touch = fopen(out[i], "w");   /* ct_spawn opens it without creating it */
    if (touch) fclose(touch);
    const char *argv[] = {ct_bin, "linearize", i ? ctl : scene, "--speed", "3", NULL};
    AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, out[i], NULL, NULL)), 0);
    AP_CHECK_EQ_INT(read_lin(out[i], A[i], B[i]), 0);
  }
  /* states: x y tilt heading rear_wheel front_frame front_wheel wx rear_rate steer_rate */
  /* the text has 6 significant digits (%g): each number is off by up to 5e-6 of itself */
  double worst = 0, amax = 0;
  for (int r = 0; r < NX; r++)
    for (int c = 0; c < NX; c++) amax = fmax(amax, fabs(A[1][r][c]));
  for (int r = 0; r < NX; r++)
    for (int c = 0; c < NX; c++) {
      double k = c == 2 ? k1 : c == 7 ? k2 : 0, want = A[0][r][c] + k * B[0][r][1];
      double tol = 5e-6 * (fabs(A[1][r][c]) + fabs(A[0][r][c]) + k * fabs(B[0][r][1])) +
                 1e-12 * amax;   /* entries of round-off (the error estimates are 4e-13 max |A|) */
      AP_CHECK_LE(fabs(A[1][r][c] - want), tol);
      worst = fmax(worst, fabs(A[1][r][c] - want) / tol);
    }
  printf("atan2 lean controller at upright, 3 m/s: |A - (A_open + B K)| within %.2f of the "
         "printed digits' rounding\n", worst);
  AP_CHECK(fabs(A[1][7][2] - A[0][7][2]) > 10);   /* the controller does act */
  remove(out[0]), remove(out[1]), remove(ctl);
}

/* ---- 5. events on body quantities -------------------------------------------------------- */

static void test_body_event(const char *src) {
  char scene[1200], ev[200], line[1024];
  snprintf(scene, sizeof scene, "%s/examples/scenes/bicycle_falling.yaml", src);
  snprintf(ev, sizeof ev, "%s/bicycle_events.yaml", ct_tmp);
  FILE *in = fopen(scene, "r"), *o = fopen(ev, "w");
  AP_CHECK(in && o);
  while (in && o && fgets(line, sizeof line, in)) fputs(line, o);
  if (o)   /* roll = atan2(B32, B33) of the body axes B = R(q) Rx(90 deg)^T */
    fputs("events:\n  body: {when: \"rear_frame.roll - 0.5\", action: log}\n"
          "  quat: {when: \"atan2(2*(rear_frame.qx*rear_frame.qx + rear_frame.qy*rear_frame.qy)"
          " - 1, 2*(rear_frame.qy*rear_frame.qz + rear_frame.qw*rear_frame.qx)) - 0.5\", "
          "action: log}\n", o);
  if (in) fclose(in);
  if (o) fclose(o);
  ap_scene *sc = NULL;
  ap_sim *s = load_sim(ev, &sc);
  if (s) AP_CHECK_EQ_INT(ap_sim_advance(s, 10.0), AP_STOPPED);
  double t[2] = {NAN, NAN};
  for (int i = 0; s && i < ap_sim_event_count(s); i++) {
    ap_event_record r;
    AP_CHECK_EQ_INT(ap_sim_event_get(s, i, &r), AP_OK);
    if (strcmp(r.name, "body") == 0) t[0] = r.t;
    if (strcmp(r.name, "quat") == 0) t[1] = r.t;
  }
  printf("event on rear_frame.roll at t = %.15f, on the quaternion's roll at %.15f\n", t[0], t[1]);
  AP_CHECK(t[0] > 1.0 && t[0] < 1.6);
  AP_CHECK_NEAR(t[0], t[1], 1e-12);
  ap_sim_free(s);
  ap_scene_free(sc);
  remove(ev);
}

int main(void) {
  char src[1024], path[1200];
  if (ct_init("expr_scene") != 0) return 1;
  ct_find_source(src, sizeof src);
  snprintf(path, sizeof path, "%s/tests/scenes/kinks_fn.yaml", src);
  test_kinks(path);
  snprintf(path, sizeof path, "%s/tests/scenes/act_body.yaml", src);
  test_body_quantities(path);
  test_channels(src);
  test_lean_controller(src);
  test_body_event(src);
  ct_finish();
  return ap_check_finish("test_expr_scene");
}
