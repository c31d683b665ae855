/* Joint kinds: local coordinates, motion columns, transforms and the kinematic matrix N.
 *
 * A joint moves its child joint frame F_C relative to its parent joint frame F_P by a rotation
 * Rj and a translation tj (F_P axes). Its speeds vj give the relative angular velocity
 * R_FP Sw vj and the rate of tj as R_FP Sv vj (world axes); columns of Sw, Sv per kind:
 *
 *   revolute   sw = axis                 prismatic  sv = axis
 *   planar     sv = e_x, e_y; sw = e_z   ball       sw = e_x, e_y, e_z
 *   free       sv = e_x, e_y, e_z; sw = e_x, e_y, e_z
 *   plane contact (parent ground, frames identity): sv = e_x, e_y for (vx, vy); for the
 *     angular speeds sw = e_i and sv = (e_z x rc)_i e_z, since z = sigma(-R^T e_z) gives
 *     z' = (e_z x rc) . w with rc = R c_b the contact vector.
 *
 * q' = N v: scalar coordinates have N = 1 against their own speed; a quaternion has the 4 x 3
 * block of q' = 1/2 [0; w] (x) q (rot.c). Local coordinate i < ndrivable is the scalar whose
 * rate is local speed i, which is what makes it drivable.
 * Generic in the scalar (model/model.h; joint_cs.c): columns, transforms and N; the counts and
 * names are double build only. */
#include <string.h>

#include "model/model.h"

#ifndef AP_SC_COMPLEX
void ap_joint_counts(ap_joint_kind kind, int *nq, int *nv, int *ndrivable, int *quat,
                     int *wofs) {
  static const int tab[7][5] = {
      /* nq nv drivable quat wofs */
      {7, 6, 3, 3, 3},    /* FREE */
      {0, 0, 0, -1, 0},   /* FIXED */
      {1, 1, 1, -1, 0},   /* REVOLUTE */
      {1, 1, 1, -1, 0},   /* PRISMATIC */
      {3, 3, 3, -1, 0},   /* PLANAR */
      {4, 3, 0, 0, 0},    /* BALL */
      {6, 5, 2, 2, 2},    /* PLANE_CONTACT */
  };
  int i = (int)kind >= 0 && (int)kind < 7 ? (int)kind : 1;
  *nq = tab[i][0], *nv = tab[i][1], *ndrivable = tab[i][2], *quat = tab[i][3];
  *wofs = tab[i][4];
}

#endif

void ap_joint_column(const ap_mjoint *j, int i, const ap_sc *rc, ap_sc *sw, ap_sc *sv) {
  memset(sw, 0, 3 * sizeof *sw);
  memset(sv, 0, 3 * sizeof *sv);
  switch (j->kind) {
    case AP_JOINT_REVOLUTE: v3_copy_d(j->axis, sw); break;
    case AP_JOINT_PRISMATIC: v3_copy_d(j->axis, sv); break;
    case AP_JOINT_PLANAR:
      if (i < 2) sv[i] = 1.0;
      else sw[2] = 1.0;
      break;
    case AP_JOINT_BALL: sw[i] = 1.0; break;
    case AP_JOINT_FREE:
      if (i < 3) sv[i] = 1.0;
      else sw[i - 3] = 1.0;
      break;
    case AP_JOINT_PLANE_CONTACT:
      if (i < 2) {
        sv[i] = 1.0;
      } else {
        ap_sc ez[3] = {0, 0, 1}, e[3];
        v3_cross(ez, rc, e);
        sw[i - 2] = 1.0;
        sv[2] = e[i - 2];
      }
      break;
    case AP_JOINT_FIXED: break;
  }
}

void ap_joint_transform(const ap_mjoint *j, const ap_sc *ql, ap_sc *Rj, ap_sc *tj) {
  static const ap_sc I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  static const double ez[3] = {0, 0, 1};
  memcpy(Rj, I3, sizeof I3);
  memset(tj, 0, 3 * sizeof *tj);
  switch (j->kind) {
    case AP_JOINT_FIXED: break;
    case AP_JOINT_REVOLUTE: ap_rot_axis_angle(j->axis, ql[0], Rj); break;
    case AP_JOINT_PRISMATIC: v3_axpy_d(ql[0], j->axis, tj); break;
    case AP_JOINT_PLANAR:
      ap_rot_axis_angle(ez, ql[2], Rj);
      tj[0] = ql[0], tj[1] = ql[1];
      break;
    case AP_JOINT_BALL: ap_quat_normalized_matrix(ql, Rj); break;
    case AP_JOINT_FREE:
      ap_quat_normalized_matrix(ql + 3, Rj);
      v3_copy(ql, tj);
      break;
    case AP_JOINT_PLANE_CONTACT:
      ap_quat_normalized_matrix(ql + 2, Rj);
      tj[0] = ql[0], tj[1] = ql[1];   /* tj[2] from the shape, by the kinematics */
      break;
  }
}

void ap_joint_fill_N(const ap_mjoint *j, const ap_sc *q, ap_sc *N, int n) {
  for (int i = 0; i < j->ndrivable; i++)
    if (j->qidx[i] >= 0) N[j->qidx[i] + (size_t)j->vidx[i] * n] = 1.0;
  if (j->quat >= 0)
    ap_quat_N(q + j->qidx[j->quat], N, n, j->qidx[j->quat], j->vidx[j->wofs]);
}

#ifndef AP_SC_COMPLEX
const char *ap_joint_kind_name(ap_joint_kind kind) {
  static const char *const names[] = {"free", "fixed", "revolute", "prismatic", "planar",
                                      "ball", "plane contact"};
  return (int)kind >= 0 && (int)kind < 7 ? names[kind] : "unknown";
}

const char *ap_joint_coord_name(ap_joint_kind kind, int i) {
  static const char *const quat[] = {"qw", "qx", "qy", "qz"};
  static const char *const xyz[] = {"x", "y", "z"};
  switch (kind) {
    case AP_JOINT_REVOLUTE: return "angle";
    case AP_JOINT_PRISMATIC: return "pos";
    case AP_JOINT_PLANAR: return i < 2 ? xyz[i] : "heading";
    case AP_JOINT_BALL: return quat[i & 3];
    case AP_JOINT_FREE: return i < 3 ? xyz[i] : quat[(i - 3) & 3];
    case AP_JOINT_PLANE_CONTACT: return i < 2 ? xyz[i] : quat[(i - 2) & 3];
    default: return "?";
  }
}

const char *ap_joint_speed_name(ap_joint_kind kind, int i) {
  static const char *const w[] = {"wx", "wy", "wz"};
  static const char *const v[] = {"vx", "vy", "vz"};
  static const char *const planar[] = {"x_dot", "y_dot", "heading_dot"};
  switch (kind) {
    case AP_JOINT_REVOLUTE: return "angle_dot";
    case AP_JOINT_PRISMATIC: return "pos_dot";
    case AP_JOINT_PLANAR: return planar[i % 3];
    case AP_JOINT_BALL: return w[i % 3];
    case AP_JOINT_FREE: return i < 3 ? v[i] : w[(i - 3) % 3];
    case AP_JOINT_PLANE_CONTACT: return i < 2 ? v[i] : w[(i - 2) % 3];
    default: return "?";
  }
}
#endif
