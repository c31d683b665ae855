/* Scene initial state: people's coordinates -> a consistent (q0, v0).
 *
 * Orientation conventions (docs/scenes.md "Initial state"): heading, tilt, spin are Z-X-Z
 * Euler angles, R = Rz(heading) Rx(tilt) Rz(spin) (intrinsic: turn about z by heading, then
 * about the new x by tilt, then about the body z by spin), so tilt is the angle between the
 * body z axis and the parent z axis: a disk or wheel (axis along body z) stands upright at
 * tilt = 90 deg and then rolls along Rz(heading) e_x. yaw, pitch, roll are Z-Y-X Tait-Bryan
 * angles, R = Rz(yaw) Ry(pitch) Rx(roll). R maps body to parent axes; quaternions [w x y z].
 *
 * Steps: (1) write each joint's coordinates and given speeds into q0, v0 (driven coordinates
 * are not in q; the others keep their local order); (2) put q on its manifold
 * (ap_body_project_q: unit quaternions, loop closures); (3) complete the speeds not given
 * (minimum norm, ap_body_complete_speeds) or, when the given ones over-determine the motion,
 * project v onto A v + a0 = 0 in the metric g (ap_project_speeds). Every correction is
 * reported; a state with no consistent speeds is refused. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static void quat_axis(int axis, double angle, double q[4]) {
  q[0] = cos(0.5 * angle), q[1] = q[2] = q[3] = 0.0;
  q[1 + axis] = sin(0.5 * angle);
}

void sc_euler_to_quat(int zyx, const double e[3], double q[4]) {
  double a[4], b[4], c[4], ab[4];
  quat_axis(2, e[0], a);
  quat_axis(zyx ? 1 : 0, e[1], b);
  quat_axis(zyx ? 0 : 2, e[2], c);
  ap_quat_mul(a, b, ab);
  ap_quat_mul(ab, c, q);
}

/* w = a' e_z + b' Rz(a) e_(x|y) + c' Rz(a) R(b) e_(z|x) */
void sc_euler_rates_to_omega(int zyx, const double e[3], const double r[3], double w[3]) {
  double ca = cos(e[0]), sa = sin(e[0]), cb = cos(e[1]), sb = sin(e[1]);
  double n[3], last[3];
  if (!zyx) {
    n[0] = ca, n[1] = sa, n[2] = 0.0;                       /* Rz(a) e_x */
    last[0] = sa * sb, last[1] = -ca * sb, last[2] = cb;    /* Rz(a) Rx(b) e_z */
  } else {
    n[0] = -sa, n[1] = ca, n[2] = 0.0;                      /* Rz(a) e_y */
    last[0] = ca * cb, last[1] = sa * cb, last[2] = -sb;    /* Rz(a) Ry(b) e_x */
  }
  for (int i = 0; i < 3; i++) w[i] = r[1] * n[i] + r[2] * last[i];
  w[2] += r[0];
}

void sc_quat_to_zxz(const double q[4], double e[3]) {
  double R[9];
  ap_quat_to_matrix(q, R);
  double s = sqrt(R[6] * R[6] + R[7] * R[7]);
  e[1] = atan2(s, R[8]);
  if (s > 1e-12) {
    e[0] = atan2(R[6], -R[7]);
    e[2] = atan2(R[2], R[5]);
  } else {                                  /* gimbal lock: the spin is folded into heading */
    e[0] = atan2(R[1], R[0]);
    e[2] = 0.0;
  }
}

/* ---- step 1: people's coordinates into q0, v0 ---------------------------------------------- */

typedef struct joint_slots {
  int qi[7], vi[6];       /* global index of each local coordinate / speed, -1 when driven */
} joint_slots;

static void slots(const ap_model *m, const sc_joint *j, int id, joint_slots *sl) {
  int q = ap_joint_coord_index(m, id), v = ap_joint_speed_index(m, id);
  for (int i = 0; i < 7; i++) sl->qi[i] = -1;
  for (int i = 0; i < 6; i++) sl->vi[i] = -1;
  int nq = 0, nv = 0;
  switch (j->def.kind) {
    case AP_JOINT_REVOLUTE: case AP_JOINT_PRISMATIC: nq = nv = 1; break;
    case AP_JOINT_PLANAR: nq = nv = 3; break;
    case AP_JOINT_BALL: nq = 4, nv = 3; break;
    case AP_JOINT_FREE: nq = 7, nv = 6; break;
    case AP_JOINT_PLANE_CONTACT: nq = 6, nv = 5; break;
    default: break;
  }
  for (int i = 0; i < nq && q >= 0; i++)
    sl->qi[i] = i < 3 && j->def.drive[i] ? -1 : q++;
  for (int i = 0; i < nv && v >= 0; i++)
    sl->vi[i] = i < 3 && j->def.drive[i] ? -1 : v++;
}

static void put(double *x, int *given, int idx, double val, int g) {
  if (idx < 0) return;
  x[idx] = val;
  if (given) given[idx] = g;
}

/* Quaternion and angular velocity (parent axes) of a joint's initial state. */
static void orientation(const sc_init *in, double quat[4], double w[3]) {
  double e[3] = {in->euler[0], in->euler[1], in->euler[2]};
  quat[0] = 1.0, quat[1] = quat[2] = quat[3] = 0.0;
  if (in->orient == 1) memcpy(quat, in->quat, sizeof in->quat);
  if (in->orient >= 2) sc_euler_to_quat(in->orient == 3, e, quat);
  w[0] = w[1] = w[2] = 0.0;
  if (in->ang == 1) memcpy(w, in->omega, sizeof in->omega);
  if (in->ang == 2) {
    double R[9], nq = sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] +
                           quat[3] * quat[3]), qn[4];
    for (int i = 0; i < 4; i++) qn[i] = quat[i] / nq;
    ap_quat_to_matrix(qn, R);
    for (int i = 0; i < 3; i++)
      w[i] = R[i] * in->omega[0] + R[i + 3] * in->omega[1] + R[i + 6] * in->omega[2];
  }
  if (in->ang == 3) sc_euler_rates_to_omega(in->orient == 3, e, in->rates, w);
}

static void place_joint(const ap_model *m, const sc_joint *j, int id, double *q, double *v,
                        int *given) {
  const sc_init *in = &j->init;
  joint_slots sl;
  slots(m, j, id, &sl);
  ap_joint_kind kind = j->def.kind;
  int lin = kind == AP_JOINT_FREE ? 3 : kind == AP_JOINT_PLANE_CONTACT ? 2
          : kind == AP_JOINT_PLANAR ? 3 : kind == AP_JOINT_BALL || kind == AP_JOINT_FIXED ? 0 : 1;
  for (int i = 0; i < lin; i++) {
    put(q, NULL, sl.qi[i], in->pos[i], 0);
    put(v, given, sl.vi[i], in->vel[i], in->vel_given[i]);
  }
  if (kind != AP_JOINT_BALL && kind != AP_JOINT_FREE && kind != AP_JOINT_PLANE_CONTACT) return;
  double quat[4], w[3];
  orientation(in, quat, w);
  for (int i = 0; i < 4; i++) put(q, NULL, sl.qi[lin + i], quat[i], 0);
  for (int i = 0; i < 3; i++) put(v, given, sl.vi[lin + i], w[i], in->ang != 0);
}

/* ---- steps 2 and 3: make it consistent ------------------------------------------------------ */

/* printf at the end of the report buffer (truncated when it is full). */
static void append(char *buf, size_t len, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void append(char *buf, size_t len, const char *fmt, ...) {
  size_t used = strlen(buf);
  if (used + 1 >= len) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf + used, len - used, fmt, ap);
  va_end(ap);
}

/* Is word in text as a whole name (row names add ".x" and the like)? */
static int names(const char *text, const char *word) {
  size_t len = strlen(word);
  for (const char *p = strstr(text, word); p; p = strstr(p + 1, word)) {
    char before = p == text ? ' ' : p[-1], after = p[len];
    int inner = (before == '_' || before == '-' || (before >= '0' && before <= '9') ||
                 (before >= 'A' && before <= 'Z') || (before >= 'a' && before <= 'z'));
    if (!inner && (after == '\0' || after == '.' || after == ' ' || after == ',' || after == ';' ||
                   after == ')' || after == ':' || after == '\''))
      return 1;
  }
  return 0;
}

/* The node to blame: a constraint the core names, else the constraints (when they are the
 * problem) or the initial state, else the top. */
static const sc_node *culprit(const sc_scene *s, const ap_data *d, int constraints) {
  for (int i = 0; d && i < s->nc; i++)
    if (names(d->msg, s->cons[i].name)) return s->cons[i].node;
  const sc_node *at = sc_map_get(s->root, constraints ? "constraints" : "initial");
  return at ? at : s->root;
}

static int refuse(sc_ctx *c, const sc_scene *s, ap_data *d, const char *what) {
  const sc_node *at = culprit(s, d, strstr(what, "constraints") != NULL);
  return sc_err(c, at, "impossible initial state: %s%s%s", what,
                d && d->msg[0] ? ": " : "", d ? d->msg : "");
}

/* The gap (m) and slip speed (relative) above which a contact with modes starts airborne or
 * sliding: the simulation's default init_tol, which chooses again at creation. */
#define SC_MODE_TOL 1e-6

/* Speeds: complete the unknown ones, or project when the given ones over-determine. */
static int consistent_speeds(sc_ctx *c, const sc_scene *s, const ap_model *m, ap_data *d,
                             double *v, const int *given, char *rep, size_t rlen) {
  int k = ap_model_k(m);
  double *v_in = malloc(sizeof(double) * (size_t)k), change = 0.0;
  if (!v_in) return sc_nomem(c);
  memcpy(v_in, v, sizeof(double) * (size_t)k);
  int rc = ap_body_complete_speeds(m, d, d->q, given, v);
  if (rc == AP_ERR_INCONSISTENT && sc_scene_has_modes(s)) {   /* contacts that slip: sliding */
    memcpy(v, v_in, sizeof(double) * (size_t)k);
    if (ap_body_contact_modes(m, d, v_in, SC_MODE_TOL) > 0)
      rc = ap_body_complete_speeds(m, d, d->q, given, v);
    if (rc == AP_OK) append(rep, rlen, "contacts whose given speeds slip start sliding\n");
  }
  if (rc == AP_ERR_INCONSISTENT) {
    memcpy(v, v_in, sizeof(double) * (size_t)k);
    rc = ap_fwd_position(m, d);
    double resid = rc == AP_OK ? ap_constraint_residual(d, v) : 0.0;
    if (rc == AP_OK) rc = ap_project_speeds(m, d, v, &change);
    if (rc == AP_OK) {
      append(rep, rlen, "the given speeds violate the constraints (max |A v + a0| = %.3g); "
             "projected onto them (change %.3g in the metric g):", resid, change);
      for (int i = 0; i < k; i++)
        if (fabs(v[i] - v_in[i]) > 1e-12 * (1.0 + fabs(v_in[i])))
          append(rep, rlen, " %s %.6g -> %.6g", ap_model_speed_name(m, i), v_in[i], v[i]);
      append(rep, rlen, "\n");
    }
  }
  free(v_in);
  if (rc == AP_ERR_NOMEM) return sc_nomem(c);
  if (rc != AP_OK) return refuse(c, s, d, "no speeds satisfy the constraints");
  if ((rc = ap_fwd_position(m, d)) != AP_OK)
    return refuse(c, s, d, "the model cannot be evaluated there");
  double resid = ap_constraint_residual(d, v), vmax = 1.0;
  for (int i = 0; i < k; i++) vmax = fmax(vmax, fabs(v[i]));
  if (resid > 1e-8 * vmax) {
    char what[128];
    snprintf(what, sizeof what, "the constraints stay violated by %.3g after projection", resid);
    return refuse(c, s, NULL, what);
  }
  return AP_OK;
}

static int consistent_state(sc_ctx *c, const sc_scene *s, const ap_model *m, ap_data *d,
                            double *q, double *v, const int *given, char *rep, size_t rlen) {
  int n = ap_model_n(m);
  double change = 0.0;
  d->t = s->run.t0;
  memcpy(d->q, q, sizeof(double) * (size_t)n);
  /* contact modes: a unilateral contact given off the ground starts airborne (not closed) */
  int rc = sc_scene_has_modes(s) ? ap_body_contact_modes(m, d, NULL, SC_MODE_TOL) : AP_OK;
  if (rc < 0) return refuse(c, s, d, "the model cannot be evaluated there");
  rc = ap_body_project_q(m, d, q, &change);
  if (rc != AP_OK) return refuse(c, s, d, "the coordinates cannot be put on their manifold");
  if (change > 1e-12)
    append(rep, rlen, "coordinates corrected by %.3g (unit quaternions, loop closures)\n",
           change);
  memcpy(d->q, q, sizeof(double) * (size_t)n);
  d->basis = AP_BASIS_ORTHONORMAL;
  if ((rc = ap_partition(m, d)) == AP_ERR_INCONSISTENT)
    return refuse(c, s, d, "the constraints contradict each other");
  if (rc == AP_ERR_RANK) return refuse(c, s, d, "the constraints leave no free speed");
  if (rc != AP_OK) return refuse(c, s, d, "the model cannot be evaluated there");
  if (ap_model_b(m) == 0) return AP_OK;
  return consistent_speeds(c, s, m, d, v, given, rep, rlen);
}

int sc_initial_state(sc_ctx *c, const sc_scene *s, const ap_model *m, double *q0, double *v0,
                     char *rep, size_t rlen) {
  int n = ap_model_n(m), k = ap_model_k(m);
  int *given = calloc((size_t)k + 1, sizeof *given);
  ap_data *d = NULL;
  if (!given || ap_data_create(m, &d) != AP_OK) {
    free(given);
    return sc_nomem(c);
  }
  memset(q0, 0, sizeof(double) * (size_t)n);
  memset(v0, 0, sizeof(double) * (size_t)k);
  if (rep && rlen) rep[0] = '\0';
  char dummy[8] = "";
  for (int j = 0; j < s->nj; j++) place_joint(m, &s->joints[j], j, q0, v0, given);
  int rc = consistent_state(c, s, m, d, q0, v0, given, rep ? rep : dummy,
                            rep ? rlen : sizeof dummy);
  ap_data_free(d);
  free(given);
  return rc;
}
