/* The maps of the chart (chart.c builds and centres it): q from the chart coordinates delta,
 * its Jacobian dq/ddelta, the chart rates from the speeds, and the heading frames of the speeds
 * (the equations are in chart.c's note).
 *
 * Generic in the scalar (linalg/scalar.h): chart_map_cs.c compiles this file again for the
 * complex-step evaluation of the reduced equations (reduced.c); q_ref and the chart's axes
 * are real in both builds. */
#include <math.h>
#include <string.h>

#include "analyze/analyze_int.h"

static void cross(const ap_sc *a, const ap_sc *b, ap_sc *c) {
  c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static void cross_d(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* The quaternion of a turn by angle about axis (ap_quat_from_axis_angle, in the scalar). */
static void quat_axis_angle(const double *axis, ap_sc angle, ap_sc *q) {
  double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  ap_sc s = n > 0 ? SC_SIN(0.5 * angle) / n : 0.0;
  q[0] = SC_COS(0.5 * angle), q[1] = s * axis[0], q[2] = s * axis[1], q[3] = s * axis[2];
  if (!(n > 0)) q[0] = 1.0;
}

/* The Hamilton product out = a (x) b (ap_quat_mul, in the scalar). */
static void quat_mul(const ap_sc *a, const ap_sc *b, ap_sc *out) {
  ap_sc w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  ap_sc x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  ap_sc y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  ap_sc z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
  out[0] = w, out[1] = x, out[2] = y, out[3] = z;
}

/* The angles (heading, tilt, spin) of quaternion chart Q from delta. */
static void angles(const an_quat *Q, const ap_sc *delta, ap_sc *a, ap_sc *b, ap_sc *c) {
  *a = delta[Q->c[0]], *b = delta[Q->c[1]], *c = delta[Q->c[2]];
}

/* M(b) = [e_z, d, cos b n0 + sin b d x n0] (3 x 3, column-major). */
static void chart_M(const an_quat *Q, ap_sc b, ap_sc *M) {
  double dn[3];
  cross_d(Q->d, Q->n0, dn);
  M[0] = 0, M[1] = 0, M[2] = 1;
  for (int i = 0; i < 3; i++)
    M[3 + i] = Q->d[i], M[6 + i] = SC_COS(b) * Q->n0[i] + SC_SIN(b) * dn[i];
}

/* x = M^-1 y by Cramer's rule (M regular: its columns are never near coplanar). */
static void solve3(const ap_sc *M, const ap_sc *y, ap_sc *x) {
  ap_sc c0[3], c1[3], c2[3];
  cross(M + 3, M + 6, c0), cross(M + 6, M, c1), cross(M, M + 3, c2);
  ap_sc det = M[0] * c0[0] + M[1] * c0[1] + M[2] * c0[2];
  x[0] = (y[0] * c0[0] + y[1] * c0[1] + y[2] * c0[2]) / det;
  x[1] = (y[0] * c1[0] + y[1] * c1[1] + y[2] * c1[2]) / det;
  x[2] = (y[0] * c2[0] + y[1] * c2[1] + y[2] * c2[2]) / det;
}

/* p = qz(a) (x) qd(b) (x) p_ref (x) qn(c). */
static void quat_chart(const an_quat *Q, const double *p_ref, ap_sc a, ap_sc b, ap_sc c,
                       ap_sc *p) {
  double ez[3] = {0, 0, 1};
  ap_sc qz[4], qd[4], qn[4], t[4], u[4], pr[4] = {p_ref[0], p_ref[1], p_ref[2], p_ref[3]};
  quat_axis_angle(ez, a, qz);
  quat_axis_angle(Q->d, b, qd);
  quat_axis_angle(Q->nb, c, qn);
  quat_mul(pr, qn, t);
  quat_mul(qd, t, u);
  quat_mul(qz, u, p);
}

/* Chart rates (a', b', c') from the parent-axes angular velocity w. */
static void quat_rates(const an_quat *Q, const ap_sc *delta, const ap_sc *w, ap_sc *out) {
  ap_sc a, b, c, M[9], ca, sa, u[3];
  angles(Q, delta, &a, &b, &c);
  ca = SC_COS(a), sa = SC_SIN(a);
  u[0] = ca * w[0] + sa * w[1], u[1] = -sa * w[0] + ca * w[1], u[2] = w[2];
  chart_M(Q, b, M);
  solve3(M, u, out);
}

/* W = Rz(a) M(b): w = W (a', b', c'). */
static void quat_W(const an_quat *Q, const ap_sc *delta, ap_sc *W) {
  ap_sc a, b, c, M[9];
  angles(Q, delta, &a, &b, &c);
  chart_M(Q, b, M);
  for (int j = 0; j < 3; j++) {
    const ap_sc *Mj = M + 3 * j;
    W[3 * j] = SC_COS(a) * Mj[0] - SC_SIN(a) * Mj[1];
    W[3 * j + 1] = SC_SIN(a) * Mj[0] + SC_COS(a) * Mj[1];
    W[3 * j + 2] = Mj[2];
  }
}

/* ---- chart maps ---------------------------------------------------------------------------- */

void ap_an_chart_apply(const an_chart *ch, int n, const double *q_ref, const ap_sc *delta,
                       ap_sc *q) {
  for (int i = 0; i < n; i++) q[i] = q_ref[i];
  for (int c = 0; c < ch->nc; c++)
    if (ch->qof[c] >= 0) q[ch->qof[c]] = q_ref[ch->qof[c]] + delta[c];
  for (int i = 0; i < ch->nquat; i++) {
    const an_quat *Q = &ch->quat[i];
    ap_sc a, b, c;
    angles(Q, delta, &a, &b, &c);
    quat_chart(Q, q_ref + Q->q, a, b, c, q + Q->q);
  }
}

void ap_an_chart_jacobian(const an_chart *ch, int n, const ap_sc *q, const ap_sc *delta,
                          ap_sc *J) {
  memset(J, 0, (size_t)n * ch->nc * sizeof *J);
  for (int c = 0; c < ch->nc; c++)
    if (ch->qof[c] >= 0) J[ch->qof[c] + (size_t)c * n] = 1.0;
  for (int i = 0; i < ch->nquat; i++) {
    const an_quat *Q = &ch->quat[i];
    const ap_sc *p = q + Q->q;
    ap_sc W[9];
    quat_W(Q, delta, W);
    for (int j = 0; j < 3; j++) {   /* dp = 1/2 [0; w] (x) p with w = W e_j */
      const ap_sc *w = W + 3 * j;
      ap_sc *col = J + (size_t)Q->c[j] * n + Q->q;
      col[0] = -0.5 * (w[0] * p[1] + w[1] * p[2] + w[2] * p[3]);
      col[1] = 0.5 * (p[0] * w[0] + w[1] * p[3] - w[2] * p[2]);
      col[2] = 0.5 * (p[0] * w[1] + w[2] * p[1] - w[0] * p[3]);
      col[3] = 0.5 * (p[0] * w[2] + w[0] * p[2] - w[1] * p[1]);
    }
  }
}

void ap_an_chart_rates(const an_chart *ch, const ap_sc *delta, const ap_sc *v, ap_sc *dd) {
  for (int c = 0; c < ch->nc; c++)
    if (ch->qof[c] >= 0) dd[c] = v[c];
  for (int i = 0; i < ch->nquat; i++) {
    const an_quat *Q = &ch->quat[i];
    ap_sc w[3] = {v[Q->c[1]], v[Q->c[2]], v[Q->c[0]]}, out[3];   /* wx, wy, wz */
    quat_rates(Q, delta, w, out);
    for (int j = 0; j < 3; j++) dd[Q->c[j]] = out[j];
  }
}

/* ---- heading frames ------------------------------------------------------------------------ */

void ap_an_frame_to_u(const an_chart *ch, const ap_sc *delta, const ap_sc *v, ap_sc *u) {
  if (u != v) memcpy(u, v, sizeof *u * (size_t)ch->k);
  for (int f = 0; f < ch->nframe; f++) {
    const an_frame *F = &ch->frame[f];
    ap_sc c = SC_COS(delta[F->h]), s = SC_SIN(delta[F->h]);
    for (int p = 0; p < F->npair; p++) {
      int i = F->pair[p][0], j = F->pair[p][1];
      ap_sc vi = v[i], vj = v[j];
      u[i] = c * vi + s * vj, u[j] = -s * vi + c * vj;
    }
  }
}

void ap_an_frame_to_v(const an_chart *ch, const ap_sc *delta, const ap_sc *u, ap_sc *v) {
  if (u != v) memcpy(v, u, sizeof *v * (size_t)ch->k);
  for (int f = 0; f < ch->nframe; f++) {
    const an_frame *F = &ch->frame[f];
    ap_sc c = SC_COS(delta[F->h]), s = SC_SIN(delta[F->h]);
    for (int p = 0; p < F->npair; p++) {
      int i = F->pair[p][0], j = F->pair[p][1];
      ap_sc ui = u[i], uj = u[j];
      v[i] = c * ui - s * uj, v[j] = s * ui + c * uj;
    }
  }
}

void ap_an_frame_rates(const an_chart *ch, const ap_sc *delta, const ap_sc *dd,
                       const ap_sc *v, const ap_sc *vdot, ap_sc *udot) {
  if (udot != vdot) memcpy(udot, vdot, sizeof *udot * (size_t)ch->k);
  for (int f = 0; f < ch->nframe; f++) {
    const an_frame *F = &ch->frame[f];
    ap_sc c = SC_COS(delta[F->h]), s = SC_SIN(delta[F->h]), hd = dd[F->h];
    for (int p = 0; p < F->npair; p++) {
      int i = F->pair[p][0], j = F->pair[p][1];
      ap_sc ui = c * v[i] + s * v[j], uj = -s * v[i] + c * v[j];
      ap_sc ai = vdot[i], aj = vdot[j];
      udot[i] = c * ai + s * aj + hd * uj, udot[j] = -s * ai + c * aj - hd * ui;
    }
  }
}

void ap_an_frame_matrix(const an_chart *ch, const ap_sc *delta, int b, const ap_sc *A,
                        ap_sc *Au) {
  size_t bb = (size_t)b;
  memcpy(Au, A, sizeof *Au * bb * (size_t)ch->k);
  for (int f = 0; f < ch->nframe; f++) {
    const an_frame *F = &ch->frame[f];
    ap_sc c = SC_COS(delta[F->h]), s = SC_SIN(delta[F->h]);
    for (int p = 0; p < F->npair; p++) {
      const ap_sc *Ai = A + bb * F->pair[p][0], *Aj = A + bb * F->pair[p][1];
      ap_sc *Ui = Au + bb * F->pair[p][0], *Uj = Au + bb * F->pair[p][1];
      for (int r = 0; r < b; r++) Ui[r] = c * Ai[r] + s * Aj[r], Uj[r] = -s * Ai[r] + c * Aj[r];
    }
  }
}
