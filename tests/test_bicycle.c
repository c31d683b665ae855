/* The Whipple bicycle built from bodies (examples/scenes/bicycle.yaml, docs/vehicles.md)
 * against the nonlinear benchmark of Basu-Mandal, Chatterjee and Papadopoulos, Proc. R. Soc. A
 * 463 (2007) 1983-2003, Table 1: one state of the benchmark bicycle of Meijaard et al. 2007
 * and its nine accelerations, and energy conservation over 10 s of riding.
 *
 * Their coordinates: the rear wheel centre (x, y, z), world z up; the rear frame's Z-X-Z Euler
 * angles theta (yaw), psi (lean, pi/2 upright), phi (pitch, pi in the upright reference
 * configuration), whose third axis is the rear axle pointing LEFT; the steer angle psi_f
 * (+ turns left) and the wheel angles beta_r, beta_f relative to their frames (+ rolling
 * forward). At theta = 0 the bicycle faces -x. The scene's world is theirs turned by pi about
 * the vertical (x_a = -x, y_a = -y, z_a = z: it faces +x at heading 0), and its free joint's
 * frame on the rear frame is theirs turned by pi about its forward axis (y up, z along the
 * axle pointing right). So the scene's rear-frame rotation is
 *     R_a = Rz(pi) R_b Rx(pi),  R_b = Rz(theta) Rx(psi) Rz(phi),
 * which is Rz(theta) Rx(pi - psi) Rz(pi - phi): heading theta, tilt pi - psi, spin pi - phi;
 * angular velocities map as w_a = Rz(pi) w_b; steer = -psi_f; wheel angles = beta_r, beta_f.
 *
 * The mapping is checked before the accelerations are compared, by quantities that do not use
 * the body model: an independent kinematic model in their coordinates (ref_bodies below,
 * velocities by complex-step differentiation, exact to round-off) gives the kinetic and
 * potential energies, the contact heights and the no-slip velocities at their state; the
 * scene's model at the mapped state must give the same energies and residuals, and their z
 * must equal r_R sin(psi). Their 13-digit state satisfies the constraints to about 5e-14: it
 * is projected first (the rear wheel centre's height and the pitch from the contact rows;
 * the dependent speeds from A v = 0 with the lean rate, steer rate and rear wheel rate kept).
 *
 * Converting the accelerations is exact algebra: the linear ones flip as the positions do;
 * the Euler angles' second derivatives come from the angular acceleration w' (their world
 * axes) by differentiating w = theta' e_z + psi' n + phi' a (n = Rz(theta) e_x the line of
 * nodes, a the body-fixed axle):
 *     w' = theta'' e_z + psi'' n + phi'' a + theta' psi' (e_z x n) + phi' (w x a),
 * a 3 x 3 solve with the columns e_z, n, a (regular away from psi = 0, pi).
 *
 * Riding the bicycle (energy over 10 s, Meijaard's linearized equations): test_bicycle_ride.c. */
#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

/* Basu-Mandal's Table 1: x y z theta psi phi psi_f beta_r beta_f; rates; accelerations. */
enum { BX, BY, BZ, BTH, BPSI, BPHI, BPSF, BBR, BBF };
static const char *const basu_names[9] = {"x", "y", "z", "theta", "psi", "phi", "psi_f",
                                          "beta_r", "beta_f"};
static const double basu_q[9] = {0, 0, 0.2440472102925, 0, 0.9501292851472, 3.1257073014894,
                                 0.2311385135743, 0, 0};
static const double basu_qd[9] = {-2.8069345714545, -0.1480982396001, 0.1058778746261,
                                  0.7830033527065, 0.6068425835418, -0.0119185528069,
                                  0.4859824687093, 8.9129896614890, 8.0133620584155};
static const double basu_qdd[9] = {-0.5041626315047, -0.3449706619454, -1.4604528332980,
                                   0.8353281706379, -7.8555281128244, 0.1205543897884,
                                   -4.6198904039403, 1.8472554144217, 2.4548072904550};

/* ---- an independent model in their coordinates (Meijaard's Table 1 in Meijaard's axes) ---- */

/* Meijaard's axes: x forward, y right, z down, origin at the rear contact. */
static const double w_base = 1.02, trail = 0.08, r_rear = 0.3, r_front = 0.35, grav = 9.81;
static const double pi = 3.14159265358979323846;
#define LAMBDA (pi / 10)
static const double mass[4] = {85, 2, 4, 3};  /* B, R, H, F */
static const double inertia[4][3][3] = {
    {{9.2, 0, 2.4}, {0, 11, 0}, {2.4, 0, 2.8}},
    {{0.0603, 0, 0}, {0, 0.12, 0}, {0, 0, 0.0603}},
    {{0.05892, 0, -0.00756}, {0, 0.06, 0}, {-0.00756, 0, 0.00708}},
    {{0.1405, 0, 0}, {0, 0.28, 0}, {0, 0, 0.1405}}};

typedef double complex cx;

static void mat_mul(const cx a[3][3], const cx b[3][3], cx out[3][3]) {
  cx t[3][3];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) t[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
  memcpy(out, t, sizeof t);
}

static void mat_vec(const cx a[3][3], const cx v[3], cx out[3]) {
  cx t[3];
  for (int i = 0; i < 3; i++) t[i] = a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2];
  memcpy(out, t, sizeof t);
}

/* Rotation by angle t about coordinate axis `ax` (0 x, 1 y, 2 z). */
static void rot_axis(int ax, cx t, cx R[3][3]) {
  int i = (ax + 1) % 3, j = (ax + 2) % 3;
  memset(R, 0, 9 * sizeof(cx));
  R[ax][ax] = 1, R[i][i] = R[j][j] = ccos(t), R[i][j] = -csin(t), R[j][i] = csin(t);
}

/* Rotation by t about the unit axis s (Rodrigues). */
static void rot_about(const double s[3], cx t, cx R[3][3]) {
  cx c = ccos(t), sn = csin(t);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) R[i][j] = (i == j ? c : 0) + (1 - c) * s[i] * s[j];
  R[0][1] -= sn * s[2], R[1][0] += sn * s[2];
  R[0][2] += sn * s[1], R[2][0] -= sn * s[1];
  R[1][2] -= sn * s[0], R[2][1] += sn * s[0];
}

/* Body com positions and rotations (Meijaard's axes -> their world axes) of B, R, H, F at
 * their coordinates c, and the wheel centres. Their rear frame's Z-X-Z frame is x forward,
 * y down, z left at the reference (phi = pi), so a vector with Meijaard components v_M has
 * the frame components T v_M = (v_x, v_z, -v_y). */
static void ref_bodies(const cx c[9], cx com[4][3], cx R[4][3][3], cx centre[2][3]) {
  cx A[3][3], T[3][3] = {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}}, S[3][3], W[3][3];
  rot_axis(2, c[BTH], R[0]);
  rot_axis(0, c[BPSI], A), mat_mul(R[0], A, R[0]);
  rot_axis(2, c[BPHI], A), mat_mul(R[0], A, R[0]);
  mat_mul(R[0], T, R[0]);                         /* R_B: Meijaard's axes of B */
  const cx P[3] = {c[BX], c[BY], c[BZ]};          /* rear wheel centre */
  /* Points relative to the rear wheel centre in B's Meijaard axes. */
  const double sdir[3] = {sin(LAMBDA), 0, cos(LAMBDA)};   /* steer axis, pointing down */
  const cx Sp[3] = {w_base + trail, 0, r_rear};           /* its ground point */
  const cx hB[3] = {0.3, 0, -0.9 + r_rear}, hH[3] = {0.9, 0, -0.7 + r_rear},
           hF[3] = {w_base, 0, r_rear - r_front};
  rot_about(sdir, -c[BPSF], S);                   /* steer: -psi_f about the downward axis */
  cx t[3], u[3];
  mat_vec(R[0], hB, t);
  for (int i = 0; i < 3; i++) com[0][i] = P[i] + t[i], com[1][i] = centre[0][i] = P[i];
  for (int body = 2; body < 4; body++) {
    const cx *h = body == 2 ? hH : hF;
    for (int i = 0; i < 3; i++) u[i] = h[i] - Sp[i];
    mat_vec(S, u, u);
    for (int i = 0; i < 3; i++) u[i] += Sp[i];
    mat_vec(R[0], u, t);
    for (int i = 0; i < 3; i++) com[body][i] = P[i] + t[i];
  }
  for (int i = 0; i < 3; i++) centre[1][i] = com[3][i];
  mat_mul(R[0], S, R[2]);                         /* R_H */
  rot_axis(1, -c[BBR], W), mat_mul(R[0], W, R[1]); /* + beta about the left axle, -y in M */
  rot_axis(1, -c[BBF], W), mat_mul(R[2], W, R[3]);
}

typedef struct ref_eval {
  double T, V;                /* kinetic and potential energy */
  double height[2];           /* rear, front: the height of the disk's lowest point (phi) */
  double slip[2];             /* |velocity of the material contact point| */
} ref_eval;

/* Energies and contact residuals of the independent model at (q, qd): velocities by complex
 * step, f(q + i h qd) = f + i h f' + O(h^2), exact to round-off for h = 1e-30. */
static void ref_evaluate(const double *q, const double *qd, ref_eval *out) {
  const double h = 1e-30;
  cx c[9], com[4][3], R[4][3][3], centre[2][3];
  for (int i = 0; i < 9; i++) c[i] = q[i] + I * h * qd[i];
  ref_bodies(c, com, R, centre);
  double w[4][3];
  memset(out, 0, sizeof *out);
  for (int b = 0; b < 4; b++) {
    double Rr[3][3], Rd[3][3], Wm[3][3], v[3];
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) Rr[i][j] = creal(R[b][i][j]), Rd[i][j] = cimag(R[b][i][j]) / h;
    for (int i = 0; i < 3; i++)          /* W = R' R^T = [w]x */
      for (int j = 0; j < 3; j++)
        Wm[i][j] = Rd[i][0] * Rr[j][0] + Rd[i][1] * Rr[j][1] + Rd[i][2] * Rr[j][2];
    w[b][0] = Wm[2][1], w[b][1] = Wm[0][2], w[b][2] = Wm[1][0];
    for (int i = 0; i < 3; i++) v[i] = cimag(com[b][i]) / h;
    double wb[3], Iw[3];                 /* body-axis angular velocity R^T w, then I R^T w */
    for (int i = 0; i < 3; i++) wb[i] = Rr[0][i] * w[b][0] + Rr[1][i] * w[b][1] + Rr[2][i] * w[b][2];
    for (int i = 0; i < 3; i++)
      Iw[i] = inertia[b][i][0] * wb[0] + inertia[b][i][1] * wb[1] + inertia[b][i][2] * wb[2];
    out->T += 0.5 * mass[b] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
              0.5 * (wb[0] * Iw[0] + wb[1] * Iw[1] + wb[2] * Iw[2]);
    out->V += mass[b] * grav * creal(com[b][2]);
  }
  for (int k = 0; k < 2; k++) {          /* wheel k: body 1 + 2k */
    int b = 1 + 2 * k;
    double r = k ? r_front : r_rear, a[3], up[3], p[3], vp[3], nu = 0;
    for (int i = 0; i < 3; i++) a[i] = creal(R[b][i][1]);   /* the axle: Meijaard's y */
    for (int i = 0; i < 3; i++) up[i] = (i == 2) - a[2] * a[i], nu += up[i] * up[i];
    nu = sqrt(nu);
    for (int i = 0; i < 3; i++) p[i] = -r * up[i] / nu;      /* contact point - centre */
    out->height[k] = creal(centre[k][2]) - r * nu;
    for (int i = 0; i < 3; i++) vp[i] = cimag(centre[k][i]) / h;
    vp[0] += w[b][1] * p[2] - w[b][2] * p[1];
    vp[1] += w[b][2] * p[0] - w[b][0] * p[2];
    vp[2] += w[b][0] * p[1] - w[b][1] * p[0];
    out->slip[k] = sqrt(vp[0] * vp[0] + vp[1] * vp[1] + vp[2] * vp[2]);
  }
}

/* ---- the scene's model and the mapping ----------------------------------------------------- */


/* Their rear-frame rotation R_b = Rz(theta) Rx(psi) Rz(phi) (row-major, real). */
static void basu_rotation(double th, double psi, double phi, double Rb[3][3]) {
  cx A[3][3], B[3][3];
  rot_axis(2, th, A);
  rot_axis(0, psi, B), mat_mul(A, B, A);
  rot_axis(2, phi, B), mat_mul(A, B, A);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) Rb[i][j] = creal(A[i][j]);
}

/* Their state (q, qd) -> the scene's (q, v). */
static void basu_to_scene(const bike *bk, const double *bq, const double *bqd, double *q,
                          double *v) {
  double Rb[3][3], Ra[9];
  basu_rotation(bq[BTH], bq[BPSI], bq[BPHI], Rb);
  /* R_a = Rz(pi) R_b Rx(pi): rows 0, 1 and columns 1, 2 change sign (column-major out). */
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) Ra[i + 3 * j] = Rb[i][j] * (i < 2 ? -1 : 1) * (j > 0 ? -1 : 1);
  q[bk->cx] = -bq[BX], q[bk->cx + 1] = -bq[BY], q[bk->cx + 2] = bq[BZ];
  ap_quat_from_matrix(Ra, q + bk->cq);
  q[bk->cR] = bq[BBR], q[bk->cH] = -bq[BPSF], q[bk->cF] = bq[BBF];
  /* w_b = theta' e_z + psi' n + phi' a; w_a = Rz(pi) w_b. */
  double n[3] = {cos(bq[BTH]), sin(bq[BTH]), 0}, wb[3];
  for (int i = 0; i < 3; i++) wb[i] = bqd[BTH] * (i == 2) + bqd[BPSI] * n[i] + bqd[BPHI] * Rb[i][2];
  v[bk->sv] = -bqd[BX], v[bk->sv + 1] = -bqd[BY], v[bk->sv + 2] = bqd[BZ];
  v[bk->sw] = -wb[0], v[bk->sw + 1] = -wb[1], v[bk->sw + 2] = wb[2];
  v[bk->sR] = bqd[BBR], v[bk->sH] = -bqd[BPSF], v[bk->sF] = bqd[BBF];
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2], c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Solve [c0 c1 c2] x = r by Cramer's rule. */
static void solve_columns(const double *c0, const double *c1, const double *c2, const double *r,
                          double x[3]) {
  double t[3];
  cross3(c1, c2, t);
  double det = dot3(c0, t);
  x[0] = dot3(r, t) / det;
  cross3(r, c2, t), x[1] = dot3(c0, t) / det;
  cross3(c1, r, t), x[2] = dot3(c0, t) / det;
}

/* The scene's (q, v, v') -> their coordinates, rates and accelerations (the inverse maps;
 * the Euler part as in the header). */
static void scene_to_basu(const bike *bk, const double *q, const double *v, const double *vd,
                          double *bq, double *bqd, double *bqdd) {
  double Ra[9], Rb[3][3];
  double qn = sqrt(dot3(q + bk->cq + 1, q + bk->cq + 1) + q[bk->cq] * q[bk->cq]), qu[4];
  for (int i = 0; i < 4; i++) qu[i] = q[bk->cq + i] / qn;
  ap_quat_to_matrix(qu, Ra);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) Rb[i][j] = Ra[i + 3 * j] * (i < 2 ? -1 : 1) * (j > 0 ? -1 : 1);
  double a[3] = {Rb[0][2], Rb[1][2], Rb[2][2]}, ez[3] = {0, 0, 1};
  bq[BPSI] = acos(Rb[2][2]);
  bq[BTH] = atan2(Rb[0][2], -Rb[1][2]);
  bq[BPHI] = atan2(Rb[2][0], Rb[2][1]);
  double n[3] = {cos(bq[BTH]), sin(bq[BTH]), 0};
  const double *w = v + bk->sw, *wd = vd + bk->sw;
  double wb[3] = {-w[0], -w[1], w[2]}, wbd[3] = {-wd[0], -wd[1], wd[2]}, e[3], r[3], t1[3], t2[3];
  solve_columns(ez, n, a, wb, e);                 /* theta', psi', phi' */
  cross3(ez, n, t1), cross3(wb, a, t2);
  for (int i = 0; i < 3; i++) r[i] = wbd[i] - e[0] * e[1] * t1[i] - e[2] * t2[i];
  solve_columns(ez, n, a, r, bqdd + BTH);         /* theta'', psi'', phi'' */
  bqd[BTH] = e[0], bqd[BPSI] = e[1], bqd[BPHI] = e[2];
  bq[BX] = -q[bk->cx], bq[BY] = -q[bk->cx + 1], bq[BZ] = q[bk->cx + 2];
  bqd[BX] = -v[bk->sv], bqd[BY] = -v[bk->sv + 1], bqd[BZ] = v[bk->sv + 2];
  bqdd[BX] = -vd[bk->sv], bqdd[BY] = -vd[bk->sv + 1], bqdd[BZ] = vd[bk->sv + 2];
  bq[BBR] = q[bk->cR], bq[BPSF] = -q[bk->cH], bq[BBF] = q[bk->cF];
  bqd[BBR] = v[bk->sR], bqd[BPSF] = -v[bk->sH], bqd[BBF] = v[bk->sF];
  bqdd[BBR] = vd[bk->sR], bqdd[BPSF] = -vd[bk->sH], bqdd[BBF] = vd[bk->sF];
}


/* ---- the checks ------------------------------------------------------------------------------ */

/* Their state as given: the independent model and the scene's model at the mapped state must
 * agree on the energies and find the contacts closed and not slipping. */
static void test_mapping(const bike *bk, ap_data *d) {
  ref_eval rf;
  ref_evaluate(basu_q, basu_qd, &rf);
  printf("their state, independent model: T = %.13f J, V = %.13f J\n", rf.T, rf.V);
  printf("  contact heights rear %.1e, front %.1e m; slip rear %.1e, front %.1e m/s; "
         "z - r_R sin(psi) = %.1e m\n", rf.height[0], rf.height[1], rf.slip[0], rf.slip[1],
         basu_q[BZ] - r_rear * sin(basu_q[BPSI]));
  for (int w = 0; w < 2; w++) {
    AP_CHECK_LE(fabs(rf.height[w]), 1e-12);
    AP_CHECK_LE(rf.slip[w], 1e-12);
  }
  AP_CHECK_LE(fabs(basu_q[BZ] - r_rear * sin(basu_q[BPSI])), 1e-12);

  /* The checks can fail: the steer with the other sign puts the front wheel off the ground,
   * and the rear wheel turning backwards makes the rear contact slip. */
  double q2[9], qd2[9];
  memcpy(q2, basu_q, sizeof q2), memcpy(qd2, basu_qd, sizeof qd2);
  q2[BPSF] = -q2[BPSF], qd2[BBR] = -qd2[BBR];
  ref_eval bad;
  ref_evaluate(q2, qd2, &bad);
  printf("  with psi_f -> -psi_f and beta_r' -> -beta_r': front height %.3g m, rear slip %.3g "
         "m/s\n", bad.height[1], bad.slip[0]);
  AP_CHECK(fabs(bad.height[1]) > 1e-3 && bad.slip[0] > 1);

  double q[10], v[9], h[2], T, V, res;
  basu_to_scene(bk, basu_q, basu_qd, q, v);
  AP_CHECK_EQ_INT(scene_eval(bk, d, q, v, h, &T, &V), AP_OK);
  AP_CHECK_EQ_INT(ap_scene_residual(bk->sc, 0, q, v, &res), AP_OK);
  printf("mapped into the scene: T = %.13f J (%.1e relative), V = %.13f J (%.1e)\n", T,
         (T - rf.T) / rf.T, V, (V - rf.V) / rf.V);
  printf("  contact rows: rear.z %.1e, front.z %.1e m; max |A v| %.1e m/s\n", h[0], h[1], res);
  AP_CHECK_NEAR(T, rf.T, 1e-12 * rf.T);
  AP_CHECK_NEAR(V, rf.V, 1e-12 * rf.V);
  for (int w = 0; w < 2; w++) AP_CHECK_LE(fabs(h[w]), 1e-12);
  AP_CHECK_LE(res, 1e-12);
}

/* Their coordinates with the rear wheel centre's height z = r_R sin(psi) and the pitch phi
 * from the front contact row (Newton with a central-difference slope), at the scene's model:
 * the drivers' projection leaves rows below 1e-12 of the length scale alone, this one closes
 * them to round-off. Returns the front row's residual. */
static double project_pitch(const bike *bk, ap_data *d, double *bq) {
  double q[10], v[9], h[2], hp[2], hm[2], step = 1e-7;
  bq[BZ] = r_rear * sin(bq[BPSI]);
  for (int it = 0; it < 6; it++) {
    basu_to_scene(bk, bq, basu_qd, q, v);
    if (scene_eval(bk, d, q, v, h, NULL, NULL) != AP_OK || h[1] == 0) break;
    double b[9];
    memcpy(b, bq, sizeof b), b[BPHI] += step;
    basu_to_scene(bk, b, basu_qd, q, v);
    AP_CHECK_EQ_INT(scene_eval(bk, d, q, v, hp, NULL, NULL), AP_OK);
    b[BPHI] -= 2 * step;
    basu_to_scene(bk, b, basu_qd, q, v);
    AP_CHECK_EQ_INT(scene_eval(bk, d, q, v, hm, NULL, NULL), AP_OK);
    bq[BPHI] -= h[1] * 2 * step / (hp[1] - hm[1]);
  }
  basu_to_scene(bk, bq, basu_qd, q, v);
  AP_CHECK_EQ_INT(scene_eval(bk, d, q, v, h, NULL, NULL), AP_OK);
  return fmax(fabs(h[0]), fabs(h[1]));
}

/* Project their state onto the constraints, evaluate, convert; the largest difference from
 * the published accelerations (printed as a table when `print`). */
static double accelerations(const bike *bk, ap_data *d, int print) {
  double q[10], v[9], bq0[9], bq[9], bqd[9], bqdd[9], zero[9] = {0};
  memcpy(bq0, basu_q, sizeof bq0);
  double phi_res = project_pitch(bk, d, bq0);
  if (print)
    printf("projected: z moved by %.1e m, phi by %.1e rad; contact rows now %.1e m\n",
           bq0[BZ] - basu_q[BZ], bq0[BPHI] - basu_q[BPHI], phi_res);
  AP_CHECK_LE(phi_res, 1e-15);
  AP_CHECK_LE(fabs(bq0[BPHI] - basu_q[BPHI]), 1e-12);
  basu_to_scene(bk, bq0, basu_qd, q, v);
  d->t = 0;
  int given[9] = {0};
  given[bk->sw] = given[bk->sR] = given[bk->sH] = 1;  /* at theta = 0, w_x = -psi' exactly */
  AP_CHECK_EQ_INT(ap_body_complete_speeds(bk->m, d, q, given, v), AP_OK);
  scene_to_basu(bk, q, v, zero, bq, bqd, bqdd);
  double dq = 0, dqd = 0;
  for (int i = 0; i < 9; i++)
    dq = fmax(dq, fabs(bq[i] - bq0[i])), dqd = fmax(dqd, fabs(bqd[i] - basu_qd[i]));
  if (print)
    printf("  speeds from A v = 0 (lean, steer and rear wheel rates kept): moved by %.1e; "
           "coordinates read back %.1e\n", dqd, dq);
  AP_CHECK_LE(dq, 1e-14);
  AP_CHECK_LE(dqd, 1e-12);
  double res;
  AP_CHECK_EQ_INT(ap_scene_residual(bk->sc, 0, q, v, &res), AP_OK);
  AP_CHECK_LE(res, 1e-14);

  memcpy(d->q, q, sizeof q), memcpy(d->v, v, sizeof v);
  d->speeds_from_e = 0;
  int rc = ap_partition(bk->m, d);
  if (rc == AP_OK) rc = ap_forward(bk->m, d);
  if (rc != AP_OK) fprintf(stderr, "ap_forward: %s\n", d->msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  scene_to_basu(bk, q, v, d->vdot, bq, bqd, bqdd);
  double worst = 0;
  if (print) printf("  %-7s %20s %20s %10s\n", "", "ours", "published", "difference");
  for (int i = 0; i < 9; i++) {
    if (print)
      printf("  %-7s %20.13f %20.13f %10.1e\n", basu_names[i], bqdd[i], basu_qdd[i],
             bqdd[i] - basu_qdd[i]);
    worst = fmax(worst, isfinite(bqdd[i]) ? fabs(bqdd[i] - basu_qdd[i]) : HUGE_VAL);
  }
  return worst;
}

/* Basu-Mandal's accelerations within 1e-10 absolute. The comparison can fail: the rear
 * frame's product of inertia with Meijaard's sign (not turned into the scene's axes) moves
 * them by far more. */
static void test_accelerations(const bike *bk, ap_data *d) {
  double worst = accelerations(bk, d, 1);
  printf("  largest difference %.1e (bound 1e-10)\n", worst);
  AP_CHECK_LE(worst, 1e-10);
  const char *set = "bodies.rear_frame.inertia=[[9.2, 0, 2.4], [0, 11, 0], [2.4, 0, 2.8]]";
  bike wrong;
  ap_data *dw = NULL;
  if (!bike_load(&wrong, &set, 1) || ap_data_create(wrong.m, &dw) != AP_OK) {
    AP_CHECK(0);
    return;
  }
  worst = accelerations(&wrong, dw, 0);
  printf("  with I_Bxz = +2.4 in the scene's axes (the sign not turned): off by %.3g\n", worst);
  AP_CHECK(worst > 1e-3);
  ap_data_free(dw);
  ap_scene_free(wrong.sc);
}


int main(void) {
  bike bk;
  ap_data *d = NULL;
  if (!bike_load(&bk, NULL, 0) || ap_data_create(bk.m, &d) != AP_OK) {
    AP_CHECK(0);
    return ap_check_finish("bicycle");
  }
  test_mapping(&bk, d);
  test_accelerations(&bk, d);
  ap_data_free(d);
  ap_scene_free(bk.sc);
  return ap_check_finish("bicycle");
}
