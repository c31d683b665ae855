/* The Whipple bicycle linearized from the nonlinear body model (examples/scenes/bicycle.yaml
 * and its linearize: section) against Meijaard, Papadopoulos, Ruina and Schwab, Proc. R. Soc.
 * A 463 (2007) 1955-1982: the eigenvalues of their Table 2 and the matrices of their §5.
 *
 * Their linearized model, q = (roll phi, steer delta), f = (roll torque T_phi, steer torque
 * T_delta):
 *
 *     M q'' + v C1 q' + (g K0 + v^2 K2) q = f.
 *
 * The linearizer's states are the chart coordinates rear_frame.tilt (phi: the Z-X-Z tilt of
 * the rear frame's joint frame is 90 deg + phi, and the chart's tilt is its offset) and
 * front_frame.angle (delta), and the heading-frame speeds rear_frame.wx (the roll rate: in the
 * chart, u_x = tilt' exactly) and front_frame.angle_dot (delta'). The inputs are a generalized
 * force on rear_frame.wx (a torque about the world x axis on the rear frame alone: T_phi, the
 * ground's roll torque) and on front_frame.angle_dot (a torque between rear and front frame
 * about the steer axis: T_delta). So in the order x = (phi, delta, phi', delta'):
 *
 *     A = [[0, I], [-M^-1 K(v), -M^-1 v C1]],   B = [[0], [M^-1]],   K(v) = g K0 + v^2 K2.
 *
 * Recovery: M = (lower block of B)^-1 (B is exact: the Appell solve is affine in the forces);
 * K(v) = -M A21(v) and v C1 = -M A22(v) at each speed; K0 = K(0) / g; over the speeds
 * v_i > 0, C1 and K2 are the least-squares fits C1 = sum v_i (v_i C1)_i / sum v_i^2 and
 * K2 = sum v_i^2 (K(v_i) - g K0) / sum v_i^4, and every speed must fit them (the residuals
 * K(v_i) - g K0 - v_i^2 K2 and (v_i C1)_i - v_i C1 are checked too: the nonlinear model's
 * linearization must be quadratic and linear in v exactly as the benchmark says).
 *
 * Derivatives: the default, the complex step, is exact to round-off; the test asserts it was
 * used. Tolerances (issue 12): eigenvalues within 1e-11 absolute of Table 2 (a 40-digit
 * recomputation, 5e-14 from the published digits); every entry of M, C1, K0, K2 within 1e-12
 * absolute of §5's. Ridders' differences (the fallback) are checked on the eigenvalues alone:
 * they reach Table 2 within 4e-13, but their error in A (1e-12 relative, times |A| ~ 20) puts
 * K0 1e-11 off, so the matrices need the complex step. Also checked: the cyclic states
 * (positions, heading, wheel angles; the pitch and the height are dependent, not states), and
 * that without the list of states the non-cyclic subsystem is the 4 x 4 block plus the rear
 * wheel's rate, whose row and column vanish (its eigenvalue is 0). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#define G 9.81
#define EIG_TOL 1e-11
#define MAT_TOL 1e-12

/* Meijaard et al. 2007, §5 (row-major 2 x 2). */
static const double M_ref[4] = {80.81722, 2.31941332208709, 2.31941332208709,
                                0.29784188199686};
static const double C1_ref[4] = {0, 33.86641391492494, -0.85035641456978, 1.68540397397560};
static const double K0_ref[4] = {-80.95, -2.59951685249872, -2.59951685249872,
                                 -0.80329488458618};
static const double K2_ref[4] = {0, 76.59734589573222, 0, 2.65431523794604};

static const char *const states4[] = {"rear_frame.tilt", "front_frame.angle", "rear_frame.wx",
                                      "front_frame.angle_dot"};

static double worst_eig = 0.0, worst_mat = 0.0, worst_fit = 0.0, worst_est = 0.0;

static int sel[4];

/* The linearization at speed v; the 4 x 4 blocks of A and B (rows and columns in the order
 * of states4) into A4 (column-major) and B4 (4 x 2). */
static int at_speed(ap_lin *L, double v, double *A4, double *B4, double *Aest) {
  int rc = ap_lin_operating_point(L, v);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc != AP_OK) {
    fprintf(stderr, "  speed %g: %s\n", v, ap_lin_message(L));
    return rc;
  }
  int nx = ap_lin_nx(L);
  const double *A = ap_lin_A(L), *E = ap_lin_A_error(L), *B = ap_lin_B(L);
  *Aest = 0.0;
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      A4[i + 4 * j] = A[sel[i] + (size_t)sel[j] * nx];
      *Aest = fmax(*Aest, E[sel[i] + (size_t)sel[j] * nx]);
    }
    for (int j = 0; j < 2; j++) B4[i + 4 * j] = B[sel[i] + (size_t)j * nx];
  }
  return AP_OK;
}

/* The eigenvalues of the 4 x 4 subsystem against ref (each matched to the nearest). */
static void check_eigs(ap_lin *L, double v, const double *re, const double *im) {
  AP_CHECK_EQ_INT(ap_lin_eigen(L, sel, 4, 1), AP_OK);
  ap_lin_eig e;
  AP_CHECK_EQ_INT(ap_lin_get_eigen(L, &e), AP_OK);
  AP_CHECK_EQ_INT(e.n, 4);
  int used[4] = {0};
  for (int i = 0; i < e.n && i < 4; i++) {
    int best = 0;
    double bd = HUGE_VAL;
    for (int j = 0; j < 4; j++)
      if (!used[j] && hypot(e.re[i] - re[j], e.im[i] - im[j]) < bd)
        bd = hypot(e.re[i] - re[j], e.im[i] - im[j]), best = j;
    used[best] = 1;
    printf("  v = %g: %.16g %+.16gi, Table 2 %.14g %+.14gi, off by %.2g (bound %.2g)\n", v,
           e.re[i], e.im[i], re[best], im[best], bd, e.err[i]);
    worst_eig = fmax(worst_eig, bd);
    AP_CHECK_LE(bd, EIG_TOL);
  }
}

static void inv2(const double *a, double *b) {   /* column-major 2 x 2 */
  double det = a[0] * a[3] - a[1] * a[2];
  b[0] = a[3] / det, b[1] = -a[1] / det, b[2] = -a[2] / det, b[3] = a[0] / det;
}

/* c = -a b (column-major 2 x 2). */
static void neg_mul2(const double *a, const double *b, double *c) {
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) c[i + 2 * j] = -(a[i] * b[2 * j] + a[i + 2] * b[1 + 2 * j]);
}

/* x (column-major) against ref (row-major) entry by entry within MAT_TOL. */
static void check_matrix(const char *name, const double *x, const double *ref) {
  double worst = 0.0;
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) {
      double d = fabs(x[i + 2 * j] - ref[2 * i + j]);
      worst = fmax(worst, d);
      if (!(d <= MAT_TOL))
        fprintf(stderr, "  %s[%d][%d] = %.17g, Meijaard %.14g, off by %.3g\n", name, i, j,
                x[i + 2 * j], ref[2 * i + j], d);
      AP_CHECK_LE(d, MAT_TOL);
    }
  printf("  %-3s recovered within %.2g of §5\n", name, worst);
  worst_mat = fmax(worst_mat, worst);
}

/* Blocks of a 4 x 4 column-major matrix: rows r0.., columns c0.. into a 2 x 2. */
static void block(const double *A4, int r0, int c0, double *b) {
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) b[i + 2 * j] = A4[(r0 + i) + 4 * (c0 + j)];
}

static void check_structure(const ap_lin *L) {
  static const char *const cyc[] = {"rear_frame.x", "rear_frame.y", "rear_frame.heading",
                                    "rear_wheel.angle", "front_wheel.angle"};
  int nx = ap_lin_nx(L), ncyc = 0;
  for (int i = 0; i < nx; i++) ncyc += ap_lin_is_cyclic(L, i);
  AP_CHECK_EQ_INT(nx, 10);
  AP_CHECK_EQ_INT(ncyc, 5);
  for (int i = 0; i < 5; i++) {
    int s = ap_lin_find_state(L, cyc[i]);
    AP_CHECK(s >= 0 && ap_lin_is_cyclic(L, s));
  }
  for (int i = 0; i < 4; i++) AP_CHECK(!ap_lin_is_cyclic(L, sel[i]));
  /* pitch and height are fixed by the contact rows: dependent, not states */
  AP_CHECK_EQ_INT(ap_lin_find_state(L, "rear_frame.spin"), -1);
  AP_CHECK_EQ_INT(ap_lin_find_state(L, "rear_frame.z"), -1);
  /* the fifth non-cyclic state, the rear wheel's rate: its row and column vanish */
  int w = ap_lin_find_state(L, "rear_wheel.angle_dot");
  AP_CHECK(w >= 0 && !ap_lin_is_cyclic(L, w));
  const double *A = ap_lin_A(L), *E = ap_lin_A_error(L);
  double amax = 0.0;
  for (int i = 0; i < nx * nx; i++) amax = fmax(amax, fabs(A[i]));
  for (int i = 0; w >= 0 && i < nx; i++) {
    if (ap_lin_is_cyclic(L, i)) continue;
    size_t rw = w + (size_t)i * nx, cw = i + (size_t)w * nx;
    AP_CHECK_LE(fabs(A[rw]), 4.0 * E[rw] + 1e-12 * amax);
    AP_CHECK_LE(fabs(A[cw]), 4.0 * E[cw] + 1e-12 * amax);
  }
  AP_CHECK_EQ_INT(ap_lin_eigen((ap_lin *)L, NULL, 0, 1), AP_OK);
  ap_lin_eig e;
  ap_lin_get_eigen(L, &e);
  AP_CHECK_EQ_INT(e.n, 5);
}

/* The sweep over v = 0 ... 10 (101 speeds) finds Table 2(a)'s characteristic speeds:
 * v_d = 0.68428307889246 (two real eigenvalues meet), the weave speed v_w = 4.29238253634111
 * (the weave pair's real part becomes negative) and the capsize speed v_c = 6.02426201538837
 * (the capsize eigenvalue becomes positive). A root moves by the eigenvalues' error over the
 * slope of the real part there (d Re/dv = -1.34 at v_w, 0.165 at v_c, from §5's matrices)
 * and the complex step's eigenvalues are within 2e-14 of Table 2 (checked above), which moves
 * v_c by 1.2e-13; the root finder's own bracket is 1e-13; the published 14 decimals are
 * rounded to 5e-15. Tolerance 1e-12 for all three (the issue asks 1e-10). */
static void check_sweep(ap_lin *L) {
  double s[101];
  for (int i = 0; i < 101; i++) s[i] = 0.1 * i;
  ap_lin_sweep sw;
  int rc = ap_lin_sweep_speed(L, s, 101, sel, 4, 1, 1e-13, &sw);
  if (rc != AP_OK) fprintf(stderr, "  sweep: %s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return;
  AP_CHECK_EQ_INT(sw.npoints, 3);
  static const struct {
    ap_lin_event kind;
    int rising, complex;
    double v, tol;
    const char *name;
  } want[3] = {{AP_LIN_MEETING, 1, 0, 0.68428307889246, 1e-12, "v_d"},
               {AP_LIN_CROSSING, 0, 1, 4.29238253634111, 1e-12, "weave v_w"},
               {AP_LIN_CROSSING, 1, 0, 6.02426201538837, 1e-12, "capsize v_c"}};
  for (int k = 0; k < 3; k++) {
    const ap_lin_point *best = NULL;
    for (int i = 0; i < sw.npoints; i++)
      if (!best || fabs(sw.points[i].p - want[k].v) < fabs(best->p - want[k].v))
        best = &sw.points[i];
    if (!best) continue;
    printf("  %-11s %.15g (+- %.1g), Table 2 %.14g, off by %.2g\n", want[k].name, best->p,
           best->p_err, want[k].v, fabs(best->p - want[k].v));
    AP_CHECK_EQ_INT(best->kind, want[k].kind);
    AP_CHECK_EQ_INT(best->rising, want[k].rising);
    AP_CHECK_EQ_INT(best->im != 0.0, want[k].complex);
    AP_CHECK_NEAR(best->p, want[k].v, want[k].tol);
  }
  ap_lin_sweep_free(&sw);
}

/* The fallback: Ridders' differences, Table 2's eigenvalues at v = 0 and 5 within 1e-11. */
static void check_ridders(const ap_scene_lin_guess *g, const double *re0, const double *im0,
                          const double *re5, const double *im5) {
  ap_lin_def def = ap_scene_lin_def(g);
  def.method = AP_LIN_RIDDERS;
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_scene_lin_create(g, &def, &L), AP_OK);
  double A4[16], B4[8], est;
  printf("Table 2 eigenvalues with Ridders' differences\n");
  if (L && at_speed(L, 0.0, A4, B4, &est) == AP_OK) {
    AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_RIDDERS);
    check_eigs(L, 0.0, re0, im0);
  }
  if (L && at_speed(L, 5.0, A4, B4, &est) == AP_OK) check_eigs(L, 5.0, re5, im5);
  ap_lin_free(L);
}

int main(void) {
  ap_scene_lin_guess g;
  char msg[1024];
  int rc = ap_scene_lin_guess_load(AP_SRCDIR "/examples/scenes/bicycle.yaml", NULL, 0, NULL, 0,
                                   &g, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK(g.dir != NULL);
  ap_lin *L = NULL;
  if (rc == AP_OK) rc = ap_scene_lin_create(&g, NULL, &L);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return ap_check_finish("lin_bicycle");
  AP_CHECK_EQ_INT(ap_lin_nu(L), 2);
  double A4[16], B4[8], est, Minv[4], M[4], K[4], K0[4];
  AP_CHECK_EQ_INT(at_speed(L, 0.0, A4, B4, &est), AP_OK);
  for (int i = 0; i < 4; i++) sel[i] = ap_lin_find_state(L, states4[i]);
  for (int i = 0; i < 4; i++) AP_CHECK(sel[i] >= 0);
  if (sel[0] < 0 || sel[1] < 0 || sel[2] < 0 || sel[3] < 0) return ap_check_finish("lin_bicycle");
  AP_CHECK_EQ_INT(at_speed(L, 0.0, A4, B4, &est), AP_OK);
  check_structure(L);

  printf("Table 2 eigenvalues\n");
  static const double re0[4] = {3.13164324790656, -3.13164324790656, 5.53094371765393,
                                -5.53094371765393}, im0[4] = {0, 0, 0, 0};
  check_eigs(L, 0.0, re0, im0);
  /* M from the input matrix, K0 from v = 0 */
  /* the default derivatives: the complex step (Ridders' reach only 1e-11 in K0, see the
   * opening comment) */
  AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_COMPLEX_STEP);
  printf("matrices of §5 (largest error estimate in the 4 x 4 block of A: %.2g at v = 0)\n",
         est);
  worst_est = est;
  block(B4, 2, 0, Minv);
  inv2(Minv, M);
  check_matrix("M", M, M_ref);
  double A21[4], A22[4];
  block(A4, 0, 2, A21);   /* the coordinate rows: phi' = phi_dot, delta' = delta_dot */
  AP_CHECK(A21[0] == 1.0 && A21[1] == 0.0 && A21[2] == 0.0 && A21[3] == 1.0);
  block(A4, 2, 0, A21);
  neg_mul2(M, A21, K);
  for (int i = 0; i < 4; i++) K0[i] = K[i] / G;
  check_matrix("K0", K0, K0_ref);

  static const double re5[4] = {-14.07838969279825, -0.77534188219584, -0.77534188219584,
                                -0.32286642900409};
  static const double im5[4] = {0, 4.46486771378823, -4.46486771378823, 0};
  static const double speeds[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  enum { NS = sizeof speeds / sizeof *speeds };
  double Kv[NS][4], Cvv[NS][4], C1[4] = {0}, K2[4] = {0}, s2 = 0, s4 = 0;
  for (int s = 0; s < NS; s++) {
    double v = speeds[s];
    AP_CHECK_EQ_INT(at_speed(L, v, A4, B4, &est), AP_OK);
    worst_est = fmax(worst_est, est);
    if (v == 5.0) check_eigs(L, v, re5, im5);
    block(A4, 2, 0, A21), block(A4, 2, 2, A22);
    neg_mul2(M, A21, Kv[s]), neg_mul2(M, A22, Cvv[s]);
    for (int i = 0; i < 4; i++) {
      C1[i] += v * Cvv[s][i], K2[i] += v * v * (Kv[s][i] - G * K0[i]);
    }
    s2 += v * v, s4 += v * v * v * v;
  }
  for (int i = 0; i < 4; i++) C1[i] /= s2, K2[i] /= s4;
  check_matrix("C1", C1, C1_ref);
  check_matrix("K2", K2, K2_ref);
  /* every speed fits K(v) = g K0 + v^2 K2 and C(v) = v C1 */
  for (int s = 0; s < NS; s++) {
    double v = speeds[s];
    for (int i = 0; i < 4; i++) {
      double dk = fabs(Kv[s][i] - G * K0[i] - v * v * K2[i]), dc = fabs(Cvv[s][i] - v * C1[i]);
      worst_fit = fmax(worst_fit, fmax(dk / (v * v), dc / v));
      AP_CHECK_LE(dk, MAT_TOL * v * v);
      AP_CHECK_LE(dc, MAT_TOL * v);
    }
  }
  check_sweep(L);
  double cs_eig = worst_eig;
  worst_eig = 0.0;
  check_ridders(&g, re0, im0, re5, im5);
  printf("Ridders' differences: eigenvalues within %.2g of Table 2\n", worst_eig);
  worst_eig = cs_eig;
  printf("bicycle linearization (complex step): eigenvalues within %.2g of Table 2 (tolerance "
         "%.0e); M, C1, K0, K2 within %.2g of §5 (tolerance %.0e); fits at 10 speeds within "
         "%.2g v^2 (K) and v (C); largest error estimate in the 4 x 4 block %.2g\n", worst_eig,
         EIG_TOL, worst_mat, MAT_TOL, worst_fit, worst_est);
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
  return ap_check_finish("lin_bicycle");
}
