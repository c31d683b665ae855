/* Rotations for the body layer: 3 x 3 products, axis-angle, quaternions [w x y z], the
 * quaternion block of N, symmetric 3 x 3 eigenvalues.
 *
 * Layout: 3 x 3 matrices column-major (R[i + 3 j] = row i, column j). A quaternion q maps
 * child components to parent components, v_parent = R(q) v_child, and with the angular
 * velocity w in parent axes R' = [w]x R, i.e. q' = 1/2 [0; w] (x) q (Hamilton product).
 * Invariant: R(q) is always computed from q / |q|, so a quaternion whose norm drifted still
 * gives an exact rotation (the projection after each step removes the drift).
 * Generic in the scalar (model/model.h): rot_cs.c compiles the products, the axis-angle, the
 * normalized quaternion matrix and N again for complex steps; the eigenvalues and the public
 * quaternion helpers are double only. */
#include <math.h>
#include <string.h>

#include "model/model.h"

void m3_mul(const ap_sc *A, const ap_sc *B, ap_sc *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = A[i] * B[3 * j] + A[i + 3] * B[1 + 3 * j] + A[i + 6] * B[2 + 3 * j];
}

void m3_mul_t(const ap_sc *A, const ap_sc *B, ap_sc *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = A[i] * B[j] + A[i + 3] * B[j + 3] + A[i + 6] * B[j + 6];
}

#ifdef AP_SC_COMPLEX
void m3_mul_d(const ap_sc *A, const double *B, ap_sc *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = A[i] * B[3 * j] + A[i + 3] * B[1 + 3 * j] + A[i + 6] * B[2 + 3 * j];
}

void m3_mul_t_d(const ap_sc *A, const double *B, ap_sc *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = A[i] * B[j] + A[i + 3] * B[j + 3] + A[i + 6] * B[j + 6];
}
#endif

/* Rodrigues: R = cos I + (1 - cos) a a^T + sin [a]x, a unit. */
void ap_rot_axis_angle(const double *a, ap_sc angle, ap_sc *R) {
  ap_sc c = SC_COS(angle), s = SC_SIN(angle), t = 1.0 - c;
  R[0] = c + t * a[0] * a[0], R[3] = t * a[0] * a[1] - s * a[2], R[6] = t * a[0] * a[2] + s * a[1];
  R[1] = t * a[1] * a[0] + s * a[2], R[4] = c + t * a[1] * a[1], R[7] = t * a[1] * a[2] - s * a[0];
  R[2] = t * a[2] * a[0] - s * a[1], R[5] = t * a[2] * a[1] + s * a[0], R[8] = c + t * a[2] * a[2];
}

void ap_quat_normalized_matrix(const ap_sc *q, ap_sc *R) {
  ap_sc nn = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  ap_sc s = SC_RE(nn) > 0 ? 2.0 / nn : 0.0;
  ap_sc w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1.0 - s * (y * y + z * z), R[3] = s * (x * y - w * z), R[6] = s * (x * z + w * y);
  R[1] = s * (x * y + w * z), R[4] = 1.0 - s * (x * x + z * z), R[7] = s * (y * z - w * x);
  R[2] = s * (x * z - w * y), R[5] = s * (y * z + w * x), R[8] = 1.0 - s * (x * x + y * y);
}

void ap_quat_N(const ap_sc *q, ap_sc *N, int ldn, int row, int col) {
  ap_sc w = 0.5 * q[0], x = 0.5 * q[1], y = 0.5 * q[2], z = 0.5 * q[3];
  ap_sc blk[4][3] = {{-x, -y, -z}, {w, z, -y}, {-z, w, x}, {y, -x, w}};
  for (int r = 0; r < 4; r++)
    for (int c = 0; c < 3; c++) N[(row + r) + (size_t)(col + c) * ldn] = blk[r][c];
}

#ifndef AP_SC_COMPLEX
/* Cyclic Jacobi rotations until the off-diagonal part is negligible; eigenvalues ascending. */
void ap_sym3_eig(const double *A, double *lam) {
  double a[3][3];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) a[i][j] = 0.5 * (A[i + 3 * j] + A[j + 3 * i]);
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
    double scale = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
    if (off <= 1e-300 || off <= 1e-17 * scale) break;
    for (int p = 0; p < 2; p++)
      for (int r = p + 1; r < 3; r++) {
        if (a[p][r] == 0.0) continue;
        double th = 0.5 * (a[r][r] - a[p][p]) / a[p][r];
        double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1.0));
        double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int i = 0; i < 3; i++) {   /* columns p, r */
          double aip = a[i][p], air = a[i][r];
          a[i][p] = c * aip - s * air, a[i][r] = s * aip + c * air;
        }
        for (int i = 0; i < 3; i++) {   /* rows p, r */
          double api = a[p][i], ari = a[r][i];
          a[p][i] = c * api - s * ari, a[r][i] = s * api + c * ari;
        }
      }
  }
  lam[0] = a[0][0], lam[1] = a[1][1], lam[2] = a[2][2];
  for (int i = 0; i < 2; i++)
    for (int j = i + 1; j < 3; j++)
      if (lam[j] < lam[i]) {
        double t = lam[i];
        lam[i] = lam[j], lam[j] = t;
      }
}

/* ---- public quaternion helpers ---------------------------------------------------------- */

void ap_quat_from_axis_angle(const double axis[3], double angle, double q[4]) {
  if (!axis || !q) return;
  double n = v3_norm(axis), s = n > 0 ? sin(0.5 * angle) / n : 0.0;
  q[0] = cos(0.5 * angle), q[1] = s * axis[0], q[2] = s * axis[1], q[3] = s * axis[2];
  if (!(n > 0)) q[0] = 1.0;
}

void ap_quat_mul(const double a[4], const double b[4], double out[4]) {
  if (!a || !b || !out) return;
  double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
  out[0] = w, out[1] = x, out[2] = y, out[3] = z;
}

void ap_quat_to_matrix(const double q[4], double R[9]) {
  if (q && R) ap_quat_normalized_matrix(q, R);
}

/* Shepperd: pick the largest of 4 w^2, 4 x^2, 4 y^2, 4 z^2 to divide by. */
void ap_quat_from_matrix(const double R[9], double q[4]) {
  if (!R || !q) return;
  double tr = R[0] + R[4] + R[8], r;
  if (tr >= R[0] && tr >= R[4] && tr >= R[8]) {
    r = sqrt(1.0 + tr);
    q[0] = 0.5 * r, q[1] = (R[5] - R[7]) / (2 * r), q[2] = (R[6] - R[2]) / (2 * r),
    q[3] = (R[1] - R[3]) / (2 * r);
  } else if (R[0] >= R[4] && R[0] >= R[8]) {
    r = sqrt(1.0 + R[0] - R[4] - R[8]);
    q[1] = 0.5 * r, q[0] = (R[5] - R[7]) / (2 * r), q[2] = (R[1] + R[3]) / (2 * r),
    q[3] = (R[2] + R[6]) / (2 * r);
  } else if (R[4] >= R[8]) {
    r = sqrt(1.0 - R[0] + R[4] - R[8]);
    q[2] = 0.5 * r, q[0] = (R[6] - R[2]) / (2 * r), q[1] = (R[1] + R[3]) / (2 * r),
    q[3] = (R[5] + R[7]) / (2 * r);
  } else {
    r = sqrt(1.0 - R[0] - R[4] + R[8]);
    q[3] = 0.5 * r, q[0] = (R[1] - R[3]) / (2 * r), q[1] = (R[2] + R[6]) / (2 * r),
    q[2] = (R[5] + R[7]) / (2 * r);
  }
  if (q[0] < 0) q[0] = -q[0], q[1] = -q[1], q[2] = -q[2], q[3] = -q[3];
}
#endif
