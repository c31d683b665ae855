/* Appell body layer (internal): the compiled body model and the layout of its per-data scratch.
 *
 * A body model is an ap_model (core/core.h) whose evaluator hooks (ev.position, ev.velocity,
 * ev.project_q) point into this layer and whose ev.impl is an ap_bmodel: immutable copies of
 * the bodies, the joints in topological order (parents first), the constraints and the
 * effects, with every index resolved at compile time. All per-evaluation state lives in the
 * data's evaluator scratch S (m->ev.scratch doubles), laid out as:
 *
 *   bodies       nb blocks of KBODY_FIXED + 9 K1 doubles (kbody below, KBODY_FIELDS)
 *   joints       nj blocks of JOINT_STRIDE (kjoint below, KJOINT_FIELDS)
 *   constraints  nc blocks of CON_STRIDE: ground motion and prescribed values at t
 *   wheels       nwheel blocks of WHEEL_STRIDE: contact geometry of the wheel contacts (kwheel,
 *                KWHEEL_FIELDS)
 *   counters     ne effect evaluation counts (stored as doubles)
 *   tmp          scratch for constraint and effect assembly
 *   proj         loop-closure projection: Jacobian, residual, step, lstsq work
 *
 * Jacobians have K1 = k + 1 columns (3 x K1, column-major): columns 0..k-1 multiply the speeds,
 * column k holds the rheonomic part (driven coordinates), so a full velocity is J [v; 1].
 * Everything is in world axes. Invariant: the velocity stage reads what the position stage
 * wrote at the same (t, q).
 *
 * Generic scalar (linalg/scalar.h, core/core.h): every function on the per-evaluation path
 * (rot, shape, joint, kinematics, constraint, contact, effect, actuator, evaluate) is written in
 * ap_sc and compiled twice; the *_cs.c wrappers give the complex-step build, whose hooks are
 * ev.position_cs, ev.velocity_cs and ev.phi_cs. Model parameters (masses, inertias, frames,
 * axes, shapes) stay double in both builds: the helpers ending in _d take a double operand.
 * Time is real: time functions (drives, ground motion, prescribed speeds, wrenches, value
 * functions) are called with a double t and give doubles. A state function's value carries
 * its exact partials (df) into the imaginary parts; user constraints and user effects are C
 * functions of doubles and make the complex-step build unavailable (ev.cs_blocker). Compile,
 * projection after steps, energies and contact forces are double only. */
#ifndef AP_MODEL_MODEL_H
#define AP_MODEL_MODEL_H

#include <math.h>
#include <stddef.h>

#include "appell/body.h"
#include "core/core.h"

/* The complex-step build's names: every function of this layer on the per-evaluation path gets
 * _cs there (the declarations below, the definitions and the calls alike). */
#ifdef AP_SC_COMPLEX
#define m3_mul m3_mul_cs
#define m3_mul_t m3_mul_t_cs
#define m3_mul_d m3_mul_d_cs
#define m3_mul_t_d m3_mul_t_d_cs
#define ap_rot_axis_angle ap_rot_axis_angle_cs
#define ap_quat_normalized_matrix ap_quat_normalized_matrix_cs
#define ap_quat_N ap_quat_N_cs
#define ap_shape_support ap_shape_support_cs
#define ap_joint_column ap_joint_column_cs
#define ap_joint_transform ap_joint_transform_cs
#define ap_joint_fill_N ap_joint_fill_N_cs
#define ap_kin_body ap_kin_body_cs
#define ap_kin_joint ap_kin_joint_cs
#define ap_kin_position ap_kin_position_cs
#define ap_kin_velocity ap_kin_velocity_cs
#define ap_kin_metric ap_kin_metric_cs
#define ap_kin_bias ap_kin_bias_cs
#define ap_kin_point ap_kin_point_cs
#define ap_kin_point_d ap_kin_point_d_cs
#define ap_kin_point_motion ap_kin_point_motion_cs
#define ap_kin_apply ap_kin_apply_cs
#define ap_con_time ap_con_time_cs
#define ap_con_rows ap_con_rows_cs
#define ap_con_gamma ap_con_gamma_cs
#define ap_con_rolling_gamma ap_con_rolling_gamma_cs
#define ap_con_loops ap_con_loops_cs
#define ap_con_ground_velocity ap_con_ground_velocity_cs
#define ap_con_ground_accel ap_con_ground_accel_cs
#define ap_contact_geom ap_contact_geom_cs
#define ap_contact_position ap_contact_position_cs
#define ap_con_contact_gamma ap_con_contact_gamma_cs
#define ap_eff_forces ap_eff_forces_cs
#define ap_act_force ap_act_force_cs
#define ap_bq_value ap_bq_value_cs
#define ap_bm_position ap_bm_position_cs
#define ap_bm_velocity ap_bm_velocity_cs
#define ap_bm_phi ap_bm_phi_cs
#endif

/* ---- tolerances (docs/bodies.md) -------------------------------------------------------- */
#define AP_QUAT_TOL 1e-9       /* re-normalize a quaternion when ||q| - 1| exceeds this: R is
                                  computed from q / |q|, so a smaller drift is harmless, and
                                  re-normalizing it would only restart the stepper */
#define AP_LOOP_TOL 1e-12      /* loop closure residual, relative to the model's length scale */
#define AP_LOOP_ITER 25        /* Gauss-Newton steps allowed in the loop projection */

/* ---- compiled elements ------------------------------------------------------------------ */

typedef struct ap_mbody {
  char name[64];
  double mass, com[3], I[9];  /* inertia about the com, body axes */
  ap_shape shape;
  int joint;                  /* index (topological) of the joint whose child this is */
  int *cols, ncols;           /* speeds that move the body (its ancestors' joints), ascending */
} ap_mbody;

typedef struct ap_mjoint {
  char name[64];
  ap_joint_kind kind;
  int id;                     /* user id */
  int parent, child;          /* body ids; parent AP_GROUND for the world */
  double Rpf[9], ppf[3];      /* parent joint frame in parent axes */
  double Rcf[9], pcf[3];      /* child joint frame in child axes */
  double axis[3];             /* revolute, prismatic (unit, parent joint frame) */
  int nq, nv;                 /* local coordinates and speeds */
  int quat;                   /* local index of the quaternion's w, or -1 */
  int wofs;                   /* local index of the first angular speed of the quaternion */
  int ndrivable;              /* scalar coordinates that may be driven (local 0..ndrivable-1) */
  int qidx[7], vidx[6];       /* global index of each local coordinate / speed; -1 = driven */
  int ndriven;
  ap_time_fn drive[3];
  void *drive_user[3];
} ap_mjoint;

typedef struct ap_mcon {
  char name[64];
  const struct ap_con_kind *kind;   /* its table of operations (con_kind.h) */
  ap_constraint_def def;      /* copy; def.name is not used */
  int row, nrows;             /* first row in A and row count */
  double dir[3];              /* unit direction (knife edge, line) or normal (plane) */
  double n1[3], n2[3];        /* point on line: unit normals of the line (body2 axes) */
  int col;                    /* prescribed speed: global speed index */
  int timed;                  /* needs time functions evaluated (ground motion, speed fn) */
  int nhol, hrow;             /* implicit holonomic rows: rows hrow..hrow+nhol-1 of the
                                 constraint (loop closures: all; wheel contacts: the last) */
  int plane;                  /* contacts: 1 when the ground plane is not z = 0 (an incline:
                                 gn . x = goff, tangents gt1, gt2 with gt1 x gt2 = gn); 2 on a
                                 fixed sphere (centre gc, radius grad, gside +1 outside, -1
                                 inside: the normal gside (o - gc) / |o - gc|); 3 on a height
                                 field (def.ground.height_fn; heightfield.c) */
  double gn[3], gt1[3], gt2[3], goff, gc[3], grad;
  int gside;
  int fric;                   /* rolling with contact modes (def.mu or def.unilateral): index of
                                 its block in the contact-mode scratch (con_friction.c); -1 */
  int wheel;                  /* contact at the shape's lowest point (rolling, knife edge with
                                 def.wheel): index of its geometry block when the body is not on
                                 a plane-contact joint, -1 when the joint carries the geometry;
                                 -2 for every other constraint */
} ap_mcon;

typedef struct ap_meff {
  char name[64];
  ap_effect_def def;
  /* joint forces and motors (actuator.c), resolved at compile */
  int col;                    /* global index of the speed acted on */
  int qcol;                   /* AP_MOTOR_ANGLE: global index of its coordinate; else -1 */
  int index;                  /* its index among the model's effects (setpoint.h) */
  int in_idx[AP_STATE_MAX_INPUTS];  /* state_fn inputs: global index in q or v ... */
  int in_v[AP_STATE_MAX_INPUTS];    /* ... of v when 1; AP_STATE_BODY: in_idx is body *
                                       AP_BODY_QTY_COUNT + quantity (body_qty.c) */
} ap_meff;

/* Code generated for one model (lib/codegen, docs/compiled.md): the kinematics of the position
 * stage with g, and of the velocity stage with h, writing the same scratch entries as
 * ap_kin_position (before the wheel contacts) + ap_kin_metric and ap_kin_velocity +
 * ap_kin_bias. position returns AP_OK or the status of a drive or a plane contact. NULL
 * on the interpreted path; double build only. */
typedef struct ap_bm_fast {
  int (*position)(const struct ap_bm_fast *f, const ap_model *m, ap_data *d, double *S);
  void (*velocity)(const struct ap_bm_fast *f, const double *v, double *S, double *h);
  /* Optional: the rest of the position stage after position (wheel contacts, time functions,
   * N, rows: A, a0) and of the velocity stage after velocity (effects: Q; gamma; friction),
   * in place of hooks.c's; NULL: hooks.c's. */
  int (*rows)(const struct ap_bm_fast *f, const ap_model *m, ap_data *d, double *S);
  int (*forces)(const struct ap_bm_fast *f, const ap_model *m, ap_data *d, double *S);
  void (*destroy)(struct ap_bm_fast *f);
} ap_bm_fast;

typedef struct ap_bmodel {
  int nb, nj, nc, ne;
  int n, k, b, K1;
  ap_mbody *bodies;           /* by body id */
  ap_mjoint *joints;          /* topological order */
  int *joint_topo;            /* user joint id -> index in joints */
  ap_mcon *cons;
  ap_meff *effs;
  int nloop;                  /* implicit holonomic rows: loop closures and wheel contacts */
  int nwheel;                 /* wheel contacts with their own geometry block */
  int nquat;                  /* joints with a quaternion */
  int has_drive;
  int ncol;                   /* Jacobian columns evaluated: K1 with drives; k without (the
                                 rheonomic column k then stays zero and is skipped) */
  int rheonomic;              /* drives or timed constraints: time-dependent terms exist */
  double lscale;              /* length scale for the loop tolerance (m) */
  int max_user_rows;
  int nfric;                  /* contacts with modes (ap_mcon.fric) */
  size_t off_fric;            /* their scratch block (con_friction.c), empty when nfric = 0 */
  size_t off_body, off_joint, off_con, off_wheel, off_cnt, off_tmp, off_proj, scratch;
  size_t body_stride, proj_work, proj_iwork;
  ap_arena layout;            /* the sections of the scratch (ap_kin_layout): off_* and scratch
                                 come from it */
  ap_bm_fast *fast;           /* compiled kinematics (lib/codegen), or NULL: interpreted */
} ap_bmodel;

/* ---- the per-element blocks of the scratch, each from one table ----------------------------
 * X(field, count) in block order; the offsets (KJ_field, KB_field, KW_field) and the strides
 * are the tables' running sums (an enum: KJ_END_f = KJ_f + count - 1, so the next field starts
 * right after), and the views below are carved from the same tables. */

/* A joint: local coordinates (7) and full speeds (6), the drivable coordinates' value, rate,
 * acceleration (3 x 3), r1, r2, r3, the driven accelerations' angular and linear parts, R_FP
 * (3 x 3), the plane contact's rc, H (3 x 3), u, cb, and the disk/torus track (3 + 1 + 1). */
#define KJOINT_FIELDS(X)                                                                   \
  X(qloc, 7) X(vloc, 6) X(drv, 9) X(r1, 3) X(r2, 3) X(r3, 3) X(adw, 3) X(adv, 3) X(RFP, 9) \
  X(rc, 3) X(H, 9) X(u, 3) X(cb, 3) X(track, 5)
/* A body: R (3 x 3), o, Iw (3 x 3), R com, w, vo, al, ao; then Jw, Jo, Jc (3 x K1 each). */
#define KBODY_FIELDS(X) X(R, 9) X(o, 3) X(Iw, 9) X(rcom, 3) X(w, 3) X(vo, 3) X(al, 3) X(ao, 3)
/* A wheel contact's geometry: u, cb, H (3 x 3), rc, track (3 + 1 + 1). */
#define KWHEEL_FIELDS(X) X(u, 3) X(cb, 3) X(H, 9) X(rc, 3) X(track, 5) X(hf, HF_STRIDE)
/* A height-field contact's ground point and frame (heightfield.c): p (x, y), whether set, h,
 * h_x, h_y, h_xx, h_xy, h_yy, n, t1, t2, dF/dp (2 x 2, column-major), |N|. */
enum { HF_P = 0, HF_SET = 2, HF_H = 3, HF_GRAD = 4, HF_HESS = 6, HF_N = 9, HF_T1 = 12,
       HF_T2 = 15, HF_J = 18, HF_NN = 22, HF_STRIDE = 23 };

#define KJ_ENUM(f, c) KJ_##f, KJ_END_##f = KJ_##f + (c) - 1,
#define KB_ENUM(f, c) KB_##f, KB_END_##f = KB_##f + (c) - 1,
#define KW_ENUM(f, c) KW_##f, KW_END_##f = KW_##f + (c) - 1,
enum { KJOINT_FIELDS(KJ_ENUM) JOINT_STRIDE };
enum { KBODY_FIELDS(KB_ENUM) KBODY_FIXED };     /* the body stride is KBODY_FIXED + 9 K1 */
enum { KWHEEL_FIELDS(KW_ENUM) WHEEL_STRIDE };
#define CON_STRIDE 8                           /* Omega, Omega', Vx, Vy, Vx', Vy', f, f' */

/* ---- views into the scratch ------------------------------------------------------------- */

typedef struct kbody {
  ap_sc *R, *o, *Iw, *rcom;   /* rotation, origin, inertia (world), R com   (position stage) */
  ap_sc *Jw, *Jo, *Jc;        /* 3 x K1: angular, origin, com Jacobians    (position stage) */
  ap_sc *w, *vo, *al, *ao;    /* angular velocity, origin velocity, bias accelerations
                                 (velocity stage) */
} kbody;

typedef struct kjoint {
  ap_sc *qloc, *vloc;         /* local coordinates (7) and full speeds (6), driven included */
  ap_sc *drv;                 /* (3 x 3) value, rate, acceleration of each drivable coordinate */
  ap_sc *r1, *r2, *r3;        /* R_p ppf, R_FP tj, R_c pcf (world) */
  ap_sc *adw, *adv;           /* driven accelerations' angular / linear contributions */
  ap_sc *RFP;                 /* parent joint frame rotation (world) */
  ap_sc *rc, *H, *u, *cb;     /* plane contact: contact vector (world), Hessian of sigma
                                 (body), u = -R^T e_z, contact point (body) */
  ap_sc *track;               /* disk, torus: the direction from the centre to the contact
                                 point (world) at the last accepted step (3), whether it is
                                 set (1), its time (1) (project_q) */
} kjoint;

/* Contact geometry of a rolling or wheel knife-edge constraint (contact.c): the joint's block
 * for a body on a plane-contact joint, the wheel block otherwise. */
typedef struct kwheel {
  ap_sc *u, *cb, *H, *rc;     /* u = -R^T e_z (body), contact point c_b = grad sigma(u) (body),
                                 Hessian of sigma (body), contact vector R c_b (world) */
  ap_sc *track;               /* disk, torus: as kjoint.track (wheel blocks only) */
  ap_sc *hf;                  /* height field: ground point and frame (HF_*; wheel blocks) */
} kwheel;

/* Each view has exactly its table's fields (kbody: and the three Jacobians). */
#define KFIELD_COUNT(f, c) +1
_Static_assert(sizeof(kjoint) == (0 KJOINT_FIELDS(KFIELD_COUNT)) * sizeof(ap_sc *),
               "kjoint and KJOINT_FIELDS list the same fields");
_Static_assert(sizeof(kbody) == (3 KBODY_FIELDS(KFIELD_COUNT)) * sizeof(ap_sc *),
               "kbody and KBODY_FIELDS list the same fields");
_Static_assert(sizeof(kwheel) == (0 KWHEEL_FIELDS(KFIELD_COUNT)) * sizeof(ap_sc *),
               "kwheel and KWHEEL_FIELDS list the same fields");

static inline const ap_bmodel *ap_bm(const ap_model *m) { return (const ap_bmodel *)m->ev.impl; }
static inline ap_sc *ap_bm_scratch(const ap_data *d) {
  return ((ap_scratch *)d->internal)->ev;
}

/* The views of body b and joint j in the scratch S (inline: a caller that reads one field
 * computes one pointer). */
static inline kbody ap_kin_body(const ap_bmodel *M, ap_sc *S, int b) {
  ap_sc *p = S + M->off_body + (size_t)b * M->body_stride;
  size_t K3 = 3 * (size_t)M->K1;
  kbody B;
#define KB_VIEW(f, c) B.f = p + KB_##f;
  KBODY_FIELDS(KB_VIEW)
#undef KB_VIEW
  B.Jw = p + KBODY_FIXED, B.Jo = B.Jw + K3, B.Jc = B.Jo + K3;
  return B;
}

static inline kjoint ap_kin_joint(const ap_bmodel *M, ap_sc *S, int j) {
  ap_sc *p = S + M->off_joint + (size_t)j * JOINT_STRIDE;
  kjoint J;
#define KJ_VIEW(f, c) J.f = p + KJ_##f;
  KJOINT_FIELDS(KJ_VIEW)
#undef KJ_VIEW
  return J;
}

/* ---- 3-vectors and 3 x 3 matrices (column-major) ---------------------------------------- */

static inline ap_sc v3_dot(const ap_sc *a, const ap_sc *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void v3_cross(const ap_sc *a, const ap_sc *b, ap_sc *c) {
  ap_sc x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
        z = a[0] * b[1] - a[1] * b[0];
  c[0] = x, c[1] = y, c[2] = z;
}
static inline ap_sc v3_norm(const ap_sc *a) { return SC_SQRT(v3_dot(a, a)); }
static inline void v3_copy(const ap_sc *a, ap_sc *b) { b[0] = a[0], b[1] = a[1], b[2] = a[2]; }
/* c += s a */
static inline void v3_axpy(ap_sc s, const ap_sc *a, ap_sc *c) {
  c[0] += s * a[0], c[1] += s * a[1], c[2] += s * a[2];
}
/* c += a x b */
static inline void v3_cross_add(const ap_sc *a, const ap_sc *b, ap_sc *c) {
  ap_sc t[3];
  v3_cross(a, b, t);
  c[0] += t[0], c[1] += t[1], c[2] += t[2];
}
/* y = M x */
static inline void m3_mul_v(const ap_sc *M, const ap_sc *x, ap_sc *y) {
  ap_sc a = M[0] * x[0] + M[3] * x[1] + M[6] * x[2], b = M[1] * x[0] + M[4] * x[1] + M[7] * x[2],
        c = M[2] * x[0] + M[5] * x[1] + M[8] * x[2];
  y[0] = a, y[1] = b, y[2] = c;
}
/* y = M^T x */
static inline void m3t_mul_v(const ap_sc *M, const ap_sc *x, ap_sc *y) {
  ap_sc a = M[0] * x[0] + M[1] * x[1] + M[2] * x[2], b = M[3] * x[0] + M[4] * x[1] + M[5] * x[2],
        c = M[6] * x[0] + M[7] * x[1] + M[8] * x[2];
  y[0] = a, y[1] = b, y[2] = c;
}
void m3_mul(const ap_sc *A, const ap_sc *B, ap_sc *C);    /* C = A B (C may not alias) */
void m3_mul_t(const ap_sc *A, const ap_sc *B, ap_sc *C);  /* C = A B^T */
void ap_rot_axis_angle(const double *axis, ap_sc angle, ap_sc *R);
void ap_quat_normalized_matrix(const ap_sc *q, ap_sc *R);  /* R of q / |q| */
/* The 4 x 3 block of N for a quaternion q with angular velocity w in parent axes:
 * q' = 1/2 [0; w] (x) q = Nq w, written into N (ld ldn) at (row, col). */
void ap_quat_N(const ap_sc *q, ap_sc *N, int ldn, int row, int col);
/* Symmetric 3 x 3 eigenvalues (Jacobi), ascending (double build only). */
void ap_sym3_eig(const double *A, double *lam);

/* The same with a double operand (a model parameter: a frame, an axis, a point, a direction);
 * in the double build they are the functions above. */
#ifdef AP_SC_COMPLEX
static inline ap_sc v3_dot_d(const ap_sc *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void v3_copy_d(const double *a, ap_sc *b) { b[0] = a[0], b[1] = a[1], b[2] = a[2]; }
static inline void v3_axpy_d(ap_sc s, const double *a, ap_sc *c) {
  c[0] += s * a[0], c[1] += s * a[1], c[2] += s * a[2];
}
static inline void v3_cross_d(const ap_sc *a, const double *b, ap_sc *c) {
  ap_sc x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
        z = a[0] * b[1] - a[1] * b[0];
  c[0] = x, c[1] = y, c[2] = z;
}
static inline void m3_mul_v_d(const ap_sc *M, const double *x, ap_sc *y) {
  ap_sc a = M[0] * x[0] + M[3] * x[1] + M[6] * x[2], b = M[1] * x[0] + M[4] * x[1] + M[7] * x[2],
        c = M[2] * x[0] + M[5] * x[1] + M[8] * x[2];
  y[0] = a, y[1] = b, y[2] = c;
}
void m3_mul_d(const ap_sc *A, const double *B, ap_sc *C);    /* C = A B */
void m3_mul_t_d(const ap_sc *A, const double *B, ap_sc *C);  /* C = A B^T */
#else
#define v3_dot_d v3_dot
#define v3_copy_d v3_copy
#define v3_axpy_d v3_axpy
#define v3_cross_d v3_cross
#define m3_mul_v_d m3_mul_v
#define m3_mul_d m3_mul
#define m3_mul_t_d m3_mul_t
#endif

/* ---- shapes (shape.c) ------------------------------------------------------------------- */

/* Support function sigma(u) of the shape at u (body axes), its gradient c (the support point)
 * and Hessian H (3 x 3). *flat = |u_perp| / |u| for disk and torus (1 otherwise). Returns 0,
 * or 1 when the shape is singular there (disk or torus lying flat: *flat < flat_tol). */
int ap_shape_support(const ap_shape *s, const ap_sc *u, ap_sc *sigma, ap_sc *c, ap_sc *H,
                     double *flat);

/* ---- joints (joint.c) ------------------------------------------------------------------- */

/* Local counts of a kind: coordinates, speeds, drivable scalars, quaternion w index, first
 * angular speed of the quaternion. */
void ap_joint_counts(ap_joint_kind kind, int *nq, int *nv, int *ndrivable, int *quat,
                     int *wofs);
/* Motion columns of local speed i in parent joint frame axes: angular sw, linear sv. For the
 * plane contact, rc is the contact vector (world = parent axes). */
void ap_joint_column(const ap_mjoint *j, int i, const ap_sc *rc, ap_sc *sw, ap_sc *sv);
/* Rotation and translation of the joint from its local coordinates (plane contact: tj[2] is
 * filled by the kinematics from the shape). */
void ap_joint_transform(const ap_mjoint *j, const ap_sc *qloc, ap_sc *Rj, ap_sc *tj);
/* The joint's entries of N (n x k, ld n) at q. */
void ap_joint_fill_N(const ap_mjoint *j, const ap_sc *q, ap_sc *N, int n);
/* Coordinate and speed names (local i) for a kind, e.g. "x", "qw"; "wx". */
const char *ap_joint_coord_name(ap_joint_kind kind, int i);
const char *ap_joint_speed_name(ap_joint_kind kind, int i);
const char *ap_joint_kind_name(ap_joint_kind kind);

/* ---- kinematics (kinematics.c) ---------------------------------------------------------- */

/* Position stage of the bodies at (t, q): drives, transforms, Jacobians, world inertias, plane
 * contacts, then the wheel contacts' support points (contact.c). Writes d->msg on failure
 * (drive callback, disk lying flat). */
int ap_kin_position(const ap_model *m, ap_data *d, double t, const ap_sc *q, ap_sc *S);
/* Velocity stage: full body velocities and bias accelerations for speeds v. */
void ap_kin_velocity(const ap_bmodel *M, const ap_sc *v, ap_sc *S);
/* g (k x k) += sum m Jc^T Jc + Jw^T Iw Jw. */
void ap_kin_metric(const ap_bmodel *M, ap_sc *S, ap_sc *g);
/* h (k) += sum Jc^T m ac + Jw^T (Iw al + w x Iw w). */
void ap_kin_bias(const ap_bmodel *M, ap_sc *S, ap_sc *h);
/* Point p (body axes) of a body or the ground: world position x, offset r = R p, Jacobian
 * JP (3 x K1) = Jo - [r]x Jw (zero for the ground). ap_kin_point_d: p a model parameter. */
void ap_kin_point(const ap_bmodel *M, ap_sc *S, int body, const ap_sc *p, ap_sc *x, ap_sc *r,
                  ap_sc *JP);
#ifdef AP_SC_COMPLEX
void ap_kin_point_d(const ap_bmodel *M, ap_sc *S, int body, const double *p, ap_sc *x,
                    ap_sc *r, ap_sc *JP);
#else
#define ap_kin_point_d ap_kin_point
#endif
/* Velocity and bias acceleration of a body point with offset r (zero for the ground). */
void ap_kin_point_motion(const ap_bmodel *M, ap_sc *S, int body, const ap_sc *r, ap_sc *vp,
                         ap_sc *ap);
/* Full velocity J [v; 1] of a 3 x K1 Jacobian. */
void ap_kin_apply(int K1, const ap_sc *J, const ap_sc *v, ap_sc *out);
/* Scratch size of the model's layout (sets the offsets in M). */
void ap_kin_layout(ap_bmodel *M);
#ifndef AP_SC_COMPLEX
/* The plane contact of joint j (index in M->joints) with joint rotation Rj: u, cb, H, rc into
 * the joint's block of S and the height *z (for the compiled kinematics, lib/codegen). */
int ap_kin_plane(const ap_model *m, ap_data *d, int j, double t, const double *Rj, double *S,
                 double *z);
/* The drives of joint j at t into its block's drv (value, rate, acceleration; lib/codegen). */
int ap_kin_drives(const ap_model *m, ap_data *d, int j, double t, double *S);
#endif
/* Doubles of the contact-mode scratch block (con_friction.c); 0 without contact modes. */
size_t ap_cfr_scratch_size(const ap_bmodel *M);

/* ---- constraints (constraint.c) --------------------------------------------------------- */

/* Time functions of the constraints at t (ground motion, prescribed speeds) into S. */
int ap_con_time(const ap_model *m, ap_data *d, double t, ap_sc *S);
/* Rows A (b x k, ld b) and a0 (b) after ap_kin_position. */
int ap_con_rows(const ap_model *m, ap_data *d, double t, const ap_sc *q, ap_sc *S, ap_sc *A,
                ap_sc *a0);
/* gamma (b) after ap_kin_velocity. */
int ap_con_gamma(const ap_model *m, ap_data *d, double t, const ap_sc *q, const ap_sc *v,
                 ap_sc *S, ap_sc *gamma);
/* Rolling (or wheel knife-edge) gamma with or without the term of the contact point moving
 * over the body surface (surface = 0 is the classic mistake; tests use it to show the
 * finite-difference check catches it; on a height field: without the ground's curvature).
 * Writes the constraint's rows of gamma. */
void ap_con_rolling_gamma(const ap_bmodel *M, ap_sc *S, int con, int surface, ap_sc *gamma);
/* Implicit holonomic rows (loop closures, wheel contact rows): residuals phi (nloop) and their
 * Jacobian transposed, JlT (k x nloop, ld k): JlT[c + k s] = d phi_s / d v_c. */
void ap_con_loops(const ap_bmodel *M, ap_sc *S, ap_sc *phi, ap_sc *JlT);
/* Ground surface velocity Vg at the world point x and its rate Ag along x' = xd, from the
 * constraint's time scratch G (zero for a fixed ground). */
enum { AP_G_OM = 0, AP_G_DOM = 1 };   /* Omega, Omega' in the constraint's time scratch */
void ap_con_ground_velocity(const ap_mcon *c, const ap_sc *G, const ap_sc *x, ap_sc *Vg);
void ap_con_ground_accel(const ap_mcon *c, const ap_sc *G, const ap_sc *x, const ap_sc *xd,
                         ap_sc *Ag);

/* ---- contacts (contact.c) --------------------------------------------------------------- */

/* The contact geometry of a rolling or wheel knife-edge constraint. */
kwheel ap_contact_geom(const ap_bmodel *M, ap_sc *S, const ap_mcon *c);
/* Support points of the wheel contacts (after the bodies' position stage); AP_RECOVERABLE with
 * a message naming the body when a disk or torus lies flat. */
int ap_contact_position(const ap_model *m, ap_data *d, double t, ap_sc *S);
/* gamma of a rolling or wheel knife-edge constraint (G: its time scratch); surface = 0 drops
 * the term of the contact point moving over the body surface (tests). */
void ap_con_contact_gamma(const ap_bmodel *M, ap_sc *S, int ci, const ap_sc *G, int surface,
                          ap_sc *gamma);

/* ---- effects (effect.c) ----------------------------------------------------------------- */

/* Q (k) += every effect's generalized force, after ap_kin_velocity. */
int ap_eff_forces(const ap_model *m, ap_data *d, double t, const ap_sc *q, const ap_sc *v,
                  ap_sc *S, ap_sc *Q);

/* ---- joint forces and motors (actuator.c) ----------------------------------------------- */

/* Validate a joint force or motor effect and resolve its indices into ef (after the joints
 * and coordinates are laid out). Fails through the builder's message. */
int ap_act_compile(ap_builder *b, const ap_bmodel *M, ap_meff *ef);
/* Q[ef->col] += tau at (t, q, v). The complex-step build carries the state function's exact
 * partials df into tau's imaginary part (AP_ERR_UNSUPPORTED, naming the effect, when the
 * function does not give them). */
int ap_act_force(const ap_model *m, ap_data *d, const ap_meff *ef, double t, const ap_sc *q,
                 const ap_sc *v, ap_sc *Q);
/* Quantity which (ap_body_qty) of body `body` from the kinematics in S (layout M; body_qty.c). */
ap_sc ap_bq_value(const ap_bmodel *M, ap_sc *S, int body, int which);

/* ---- evaluator (evaluate.c) ------------------------------------------------------------- */

int ap_bm_position(const ap_model *m, ap_data *d, ap_sc *S);
int ap_bm_velocity(const ap_model *m, ap_data *d, ap_sc *S);
/* The DAE mode's implicit holonomic constraints (core.h ev.phi): loop closures, then one
 * unit-norm row per quaternion joint; after ap_kin_position at (d->t, d->q). */
int ap_bm_phi(const ap_model *m, ap_data *d, ap_sc *S, ap_sc *phi, ap_sc *Phi_q);

/* ---- double build only: compile, projection, energies, contact forces -------------------- */
#ifndef AP_SC_COMPLEX
/* The position and velocity stages with the interpreted kinematics even when the model is
 * compiled (lib/codegen re-evaluates a stage whose one check failed, so that the core's checks
 * name the entry the interpreted path names). */
int ap_bm_position_interp(const ap_model *m, ap_data *d, double *S);
int ap_bm_velocity_interp(const ap_model *m, ap_data *d, double *S);
int ap_bm_project_q(const ap_model *m, ap_data *d, double *q, double *S, double *change);
/* The same with track = 0: no check of the contact direction between accepted steps, and the
 * tracking is reset (for assembling states by hand). */
int ap_bm_project(const ap_model *m, ap_data *d, double *q, double *S, double *change,
                  int track);
/* q += N(q) dv (dv: k speeds), quaternions re-normalized. */
void ap_bm_step_q(const ap_bmodel *M, double *q, const double *dv);
/* track_flat only (no correction of q): the DAE mode's check after each step. */
int ap_bm_check_q(const ap_model *m, ap_data *d, const double *q, double *S);
/* 0, or -1 with a message naming the user constraint or user effect that keeps the model from
 * the complex-step build (core.h ev.cs_blocker). */
int ap_bm_cs_blocker(const ap_model *m, char *msg, size_t len);
/* The complex-step hooks (hooks_cs.c), for compile.c to install. */
int ap_bm_position_cs(const ap_model *m, ap_data_cs *d, double _Complex *S);
int ap_bm_velocity_cs(const ap_model *m, ap_data_cs *d, double _Complex *S);
int ap_bm_phi_cs(const ap_model *m, ap_data_cs *d, double _Complex *S, double _Complex *phi,
                 double _Complex *Phi_q);
/* 1 when body is root or one of its descendants. */
int ap_bm_in_subtree(const ap_bmodel *M, int body, int root);
/* Potential energy of the gravity and spring effects, after ap_kin_position. */
double ap_eff_potential(const ap_bmodel *M, double *S);
/* The ground's unit normal n and tangents t1, t2 at the contact of c (contact.c). */
void ap_contact_frame(const ap_bmodel *M, double *S, const ap_mcon *c, double *n, double *t1,
                      double *t2);
/* Height-field contacts (heightfield.c, double build only): the ground point p by Newton on
 * the closest-point conditions and the contact geometry at it (position stage), the gap
 * n . (x - p), and the constraint's rows of gamma (curvature = 0 leaves out the ground's
 * curvature, n' = 0: the classic mistake, for the tests). */
int ap_hf_position(const ap_model *m, ap_data *d, double t, double *S, const ap_mcon *c);
double ap_hf_gap(const double *hf, const double *x);
void ap_hf_gamma(const ap_bmodel *M, double *S, const ap_mcon *c, int curvature,
                 double *gamma);
/* F += f and (T != NULL) T += (x - o) x f: a force f at the world point x (constraint.c). */
void ap_bm_add_force(const double *f, const double *x, const double *o, double *F, double *T);
/* Forces on the subtree of a plane-contact body (world axes), after the velocity stage: of the
 * effects (effect.c), and of the constraint rows other than skip with multipliers lambda
 * (constraint.c). AP_ERR_UNSUPPORTED when a user effect or user constraint is present (its
 * generalized force cannot be attributed to bodies). */
int ap_eff_subtree_force(const ap_bmodel *M, double *S, double t, const double *v, int root,
                         double *F);
int ap_con_subtree_force(const ap_bmodel *M, double *S, const double *lambda, int root,
                         int skip, double *F);
int ap_eff_subtree_wrench(const ap_bmodel *M, double *S, double t, const double *v, int root,
                          const double *o, double *F, double *T);
/* The same with the moment T about the world point o (T may be NULL). */
int ap_con_subtree_wrench(const ap_bmodel *M, double *S, const double *lambda, int root,
                          int skip, const double *o, double *F, double *T);
/* The normal load of wheel contact `constraint` (c->wheel >= 0, or a plane-contact body in a
 * planar chassis' group: ap_bm_plane_in_group) with multipliers lam, after
 * the pipeline at the data's state (v'): its share of what holds its chassis (loads.c), how it
 * is known, and how many contacts share it. */
int ap_bm_wheel_load(const ap_model *m, const ap_data *d, const double *lam, int constraint,
                     double *normal, ap_load_kind *kind, int *count);
/* 1 when rolling contact c is on a plane-contact body that a loop joins to a planar chassis
 * (diff_drive_loops.yaml): its load is then its share of that vehicle's, ap_bm_wheel_load. */
int ap_bm_plane_in_group(const ap_bmodel *M, const ap_mcon *c);
/* The contact point p (3, world) of a wheel contact or of a plane-contact body's contact. */
void ap_bm_contact_point(const ap_bmodel *M, double *S, const ap_mcon *c, double *p);
/* 1 when wheel contact c's normal force is its load, not its row's multiplier: a wheel under
 * a planar chassis (the joint holds the chassis up; the contact row .z vanishes). */
int ap_bm_wheel_by_load(const ap_bmodel *M, const ap_mcon *c);
/* The load of such a wheel at the accelerations vd (k) and the multipliers lam (b), after the
 * velocity stage at the data's state: affine in (vd, lam), the friction law's F_n. *unique
 * (may be NULL): 0 when the chassis' loads are statically indeterminate (minimum-norm). */
int ap_bm_wheel_load_at(const ap_model *m, const ap_data *d, const double *vd,
                        const double *lam, int constraint, double *normal, int *unique);
void ap_bm_destroy(void *impl);
#endif

/* Message helper: printf into d->msg (core). */
#define AP_BM_MSG(d, ...) AP_SC(ap_core_msg)((d), __VA_ARGS__)

#endif
