/* The chart of the configuration about a reference point, and the heading frames of the speeds.
 *
 * Body models: one chart coordinate per speed (index c = speed c). A scalar joint coordinate is
 * its offset from the reference, q_i = q_ref,i + delta_c. A unit quaternion p (angular speeds
 * w in parent joint frame axes, p' = 1/2 [0; w] (x) p) gets Euler-like angles about the
 * reference, heading a, tilt b, spin c:
 *
 *     R = Rz(a) Rd(b) R_ref Rn(c),    d = unit(e_z x n0), n0 = R_ref n,
 *
 * with n an axis of the joint's child frame (the spin axis: its z axis, unless that is within
 * 26 degrees of the vertical at the reference, then its most horizontal axis) and Rd a turn
 * about the horizontal axis d. With n = z and the reference's Z-X-Z angles (h0, t0, s0),
 * 0 < t0 < pi, d is the line of nodes Rz(h0) e_x and R = Rz(h0 + a) Rx(t0 + b) Rz(s0 + c):
 * the chart's angles are the offsets of the scene's heading, tilt and spin. Turning
 * the whole body about the parent z axis changes a alone and spinning it about n changes c
 * alone, exactly: a heading or a spin that moves at a steady motion is a true cyclic coordinate
 * (a rotation vector mixes tilt and spin at second order, which falsifies the eigenvalues of a
 * rolling disk). The angular velocity is w = a' e_z + b' Rz(a) d + c' Rz(a) Rd(b) n0, so in the
 * heading frame u_w = Rz(a)^T w = M(b) (a', b', c') with M = [e_z, d, cos b n0 + sin b d x n0],
 * regular since n0 is never near vertical. Math-level systems: q = q_ref + delta, and the chart
 * rates are q' = N v (the core's qdot).
 *
 * Heading frames: a joint with a heading (planar: its heading coordinate; ball, free, plane
 * contact: a) has its speeds along parent x and y taken in the frame turned by the heading
 * offset h: (u_x, u_y) = Rz(h)^T (v_x, v_y), for the linear and the angular pair. Then
 * u' = S v' + S' v gives u_x' = c v_x' + s v_y' + h' u_y, u_y' = -s v_x' + c v_y' - h' u_x.
 * This file builds and centres the chart (double only); the maps it defines (q from delta, its
 * Jacobian, the rates, the heading frames) are in chart_map.c, generic in the scalar. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "model/layout.h"

/* ---- building -------------------------------------------------------------------------- */

static char *dup_str(const char *a, const char *b) {
  size_t len = strlen(a) + strlen(b) + 1;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s%s", a, b);
  return s;
}

/* The heading frame of a joint: heading chart index h, pairs of speeds (-1 entries skip). */
static void add_frame(an_chart *ch, int h, int p0, int p1, int p2, int p3) {
  if (h < 0) return;
  an_frame *f = &ch->frame[ch->nframe];
  f->npair = 0;
  if (p0 >= 0 && p1 >= 0) f->pair[f->npair][0] = p0, f->pair[f->npair][1] = p1, f->npair++;
  if (p2 >= 0 && p3 >= 0) f->pair[f->npair][0] = p2, f->pair[f->npair][1] = p3, f->npair++;
  if (f->npair == 0) return;
  f->h = h;
  ch->nframe++;
}

static int chart_joint(const ap_model *m, const ap_jlayout *J, an_chart *ch) {
  static const char *const rot[3] = {".heading", ".tilt", ".spin"};
  for (int i = 0; i < J->ndrivable; i++) {
    if (J->vidx[i] < 0) continue;
    ch->qof[J->vidx[i]] = J->qidx[i];
    ch->names[J->vidx[i]] = dup_str(ap_model_coord_name(m, J->qidx[i]), "");
    if (!ch->names[J->vidx[i]]) return AP_ERR_NOMEM;
  }
  const int *v = J->vidx;
  if (J->quat >= 0) {
    an_quat *Q = &ch->quat[ch->nquat++];
    Q->q = J->qidx[J->quat];
    for (int i = 0; i < 3; i++) {
      Q->c[i] = v[J->wofs + (i + 2) % 3];   /* heading, tilt, spin: indices of wz, wx, wy */
      ch->qof[Q->c[i]] = -1;
      ch->names[Q->c[i]] = dup_str(J->name, rot[i]);
      if (!ch->names[Q->c[i]]) return AP_ERR_NOMEM;
    }
  }
  switch (J->kind) {
    case AP_JOINT_PLANAR: add_frame(ch, v[2], v[0], v[1], -1, -1); break;
    case AP_JOINT_BALL: add_frame(ch, v[2], v[0], v[1], -1, -1); break;
    case AP_JOINT_FREE: add_frame(ch, v[5], v[0], v[1], v[3], v[4]); break;
    case AP_JOINT_PLANE_CONTACT: add_frame(ch, v[4], v[0], v[1], v[2], v[3]); break;
    default: break;
  }
  return AP_OK;
}

static int chart_body(const ap_model *m, an_chart *ch, char *msg, size_t len) {
  int nj = ap_bm_joint_count(m), rc = AP_OK;
  for (int j = 0; j < nj && rc == AP_OK; j++) {
    ap_jlayout J;
    rc = ap_bm_joint_layout(m, j, &J);
    if (rc == AP_OK) rc = chart_joint(m, &J, ch);
  }
  for (int c = 0; c < ch->nc && rc == AP_OK; c++)
    if (!ch->names[c]) {
      snprintf(msg, len, "model '%s': speed '%s' belongs to no coordinate the linearization "
               "knows (joint kinds: revolute, prismatic, planar, ball, free, plane contact)",
               ap_model_name(m), ap_model_speed_name(m, c));
      rc = AP_ERR_UNSUPPORTED;
    }
  return rc;
}

int ap_an_chart_build(const ap_model *m, an_chart *ch, char *msg, size_t len) {
  int n = ap_model_n(m), k = ap_model_k(m);
  memset(ch, 0, sizeof *ch);
  ch->body = ap_model_is_body_model(m) == 1;
  ch->nc = ch->body ? k : n;
  ch->k = k;
  ch->qof = calloc((size_t)ch->nc + 1, sizeof *ch->qof);
  ch->names = calloc((size_t)ch->nc + 1, sizeof *ch->names);
  ch->quat = calloc((size_t)k / 3 + 1, sizeof *ch->quat);
  ch->frame = calloc((size_t)k / 2 + 1, sizeof *ch->frame);
  if (!ch->qof || !ch->names || !ch->quat || !ch->frame) return AP_ERR_NOMEM;
  if (ch->body) return chart_body(m, ch, msg, len);
  for (int i = 0; i < n; i++) {
    ch->qof[i] = i;
    ch->names[i] = dup_str(ap_model_coord_name(m, i), "");
    if (!ch->names[i]) return AP_ERR_NOMEM;
  }
  return AP_OK;
}

void ap_an_chart_free(an_chart *ch) {
  for (int c = 0; ch->names && c < ch->nc; c++) free(ch->names[c]);
  free(ch->names);
  free(ch->qof);
  free(ch->quat);
  free(ch->frame);
  memset(ch, 0, sizeof *ch);
}

/* ---- the quaternion chart ------------------------------------------------------------------ */

static void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* x = R(p) y for a unit quaternion p. */
static void rotate(const double *p, const double *y, double *x) {
  double R[9];
  ap_quat_to_matrix(p, R);
  for (int i = 0; i < 3; i++) x[i] = R[i] * y[0] + R[i + 3] * y[1] + R[i + 6] * y[2];
}

/* The frame's z axis is the spin axis unless it is within acos(SPIN_Z_MAX) = 26 degrees of
 * the vertical. */
#define SPIN_Z_MAX 0.9

void ap_an_chart_centre(an_chart *ch, const double *q_ref, int keep_axis) {
  for (int i = 0; i < ch->nquat; i++) {
    an_quat *Q = &ch->quat[i];
    const double *p = q_ref + Q->q;
    rotate(p, Q->nb, Q->n0);
    if (!keep_axis || !(fabs(Q->n0[2]) < 0.95)) {
      double ez[3] = {0, 0, 1}, best = 2.0;
      rotate(p, ez, Q->n0);
      if (fabs(Q->n0[2]) < SPIN_Z_MAX) best = -1.0, Q->nb[0] = Q->nb[1] = 0, Q->nb[2] = 1;
      for (int a = 0; a < 3 && best >= 0.0; a++) {   /* the most horizontal body axis */
        double e[3] = {a == 0, a == 1, a == 2}, n[3];
        rotate(p, e, n);
        if (fabs(n[2]) < best) best = fabs(n[2]), memcpy(Q->nb, e, sizeof e);
      }
      rotate(p, Q->nb, Q->n0);
    }
    double ez[3] = {0, 0, 1}, h;
    cross(ez, Q->n0, Q->d);
    h = sqrt(Q->d[0] * Q->d[0] + Q->d[1] * Q->d[1]);
    Q->d[0] /= h, Q->d[1] /= h, Q->d[2] = 0.0;
  }
}
