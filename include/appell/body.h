/* Appell: rigid bodies, joints, shapes, constraints and effects, compiled into a model.
 *
 * Users describe bodies joined to a parent (another body or the ground) by joints whose
 * coordinates become the generalized coordinates q, constraint rows (rolling, knife edge,
 * prescribed speed, loop closures, user callbacks) and effects (gravity, springs, damping,
 * applied forces). ap_builder_compile validates everything once and produces an ap_model that
 * the core (system.h) and the drivers (sim.h) use like any other: it evaluates
 *
 *     g = sum_b J_b^T M_b J_b,   h = sum_b J_b^T (M_b a_b + [w_b x I_b w_b; 0]),   Q,
 *     A, a0 and gamma = -(A' v + a0')
 *
 * from the bodies (docs/design.md §1 "Holonomic reduction from bodies"; docs/bodies.md).
 *
 * Conventions: SI units; world z is up and the ground plane is z = 0; vectors "in body axes"
 * are components in the body frame, everything else in world axes; 3 x 3 matrices are
 * column-major; quaternions are [w x y z] and map body components to parent components.
 * Definitions are filled by their *_default() function and then edited (Box2D style); one
 * that function did not make (its internal_check unset) is refused with AP_ERR_ARG. Ids are
 * small integers in the order of creation. */
#ifndef APPELL_BODY_H
#define APPELL_BODY_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/status.h"
#include "appell/system.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The parent id of a joint to the fixed world, and the "body" of a loop point in the world. */
#define AP_GROUND (-1)
/* An id field that has not been set. */
#define AP_NONE (-2)

/* A prescribed function of time: fill f[0] = value, f[1] = first and f[2] = second time
 * derivative at t. Returns 0 = ok, > 0 = recoverable (retry with a smaller step), < 0 = stop. */
typedef int (*ap_time_fn)(double t, double f[3], void *user);

/* A fixed ground height field z = h(x, y) (m, world): fill h[0] = h, h[1] = dh/dx,
 * h[2] = dh/dy, h[3] = d2h/dx2, h[4] = d2h/dxdy, h[5] = d2h/dy2 at the world point (x, y) (m).
 * Returns 0 = ok, non-zero when h is not defined there (the evaluation stops with a message). */
typedef int (*ap_height_fn)(double x, double y, double h[6], void *user);

/* A force (N, world axes) and torque (N m, world axes) at time t, for an applied effect.
 * Both arrays are zeroed before the call. Return codes as above. */
typedef int (*ap_wrench_fn)(double t, double force[3], double torque[3], void *user);

/* ------------------------------------------------------------------------------------------ */
/* Functions of the state: joint forces, joint torques and motor set-points that read joint    */
/* coordinates and speeds.                                                                     */

/* Most inputs one state function may declare. */
#define AP_STATE_MAX_INPUTS 16

/* Quantities of a body, functions of the whole state through the kinematics: what
 * ap_body_quantity returns and what a state function may read (ap_state_input with speed =
 * AP_STATE_BODY). Angles in rad, in (-pi, pi] (tilt and pitch in [0, pi] and [-pi/2, pi/2]),
 * from the body axes R (world axes):
 *   roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll) (Z-Y-X, about the world's z then the
 *     rotated y then the body's x): roll = atan2(R32, R33), pitch = atan2(-R31, hypot(R11,
 *     R21)), yaw = atan2(R21, R11);
 *   heading, tilt, spin: R = Rz(heading) Rx(tilt) Rz(spin) (Z-X-Z, as the output's `angles`
 *     channel): tilt = atan2(hypot(R13, R23), R33), heading = atan2(R13, -R23), spin =
 *     atan2(R31, R32) (at tilt 0: heading = atan2(R21, R11), spin = 0).
 * Their partial derivatives are exact (the complex-step build carries them). */
typedef enum ap_body_qty {
  AP_BODY_X = 0, AP_BODY_Y, AP_BODY_Z,          /* body origin, world axes (m) */
  AP_BODY_VX, AP_BODY_VY, AP_BODY_VZ,           /* velocity of the body origin, world (m/s) */
  AP_BODY_ROLL, AP_BODY_PITCH, AP_BODY_YAW,     /* Z-Y-X angles of the body axes (rad) */
  AP_BODY_HEADING, AP_BODY_TILT, AP_BODY_SPIN,  /* Z-X-Z angles of the body axes (rad) */
  AP_BODY_WX, AP_BODY_WY, AP_BODY_WZ,           /* angular velocity, world axes (rad/s) */
  AP_BODY_QTY_COUNT
} ap_body_qty;

/* ap_state_input.speed for a body quantity. */
#define AP_STATE_BODY 2

/* One scalar of the state that a state function reads: coordinate `index` (speed = 0) or speed
 * `index` (speed = 1) of joint `joint`, in the joint kind's local order (table under "Joints"
 * below: a revolute joint's angle is coordinate 0, its rate speed 0); or (speed =
 * AP_STATE_BODY) quantity `index` (ap_body_qty) of the body whose id is `joint`. Driven
 * coordinates and speeds are not in the state and cannot be inputs. */
typedef struct ap_state_input {
  int joint;               /* joint id (body id for AP_STATE_BODY) */
  int speed;               /* 0: a coordinate, 1: a speed, AP_STATE_BODY: a body quantity */
  int index;               /* local index within the joint, or an ap_body_qty */
} ap_state_input;

/* What a state function receives. x holds the declared inputs, gathered from q and v (body
 * quantities from the kinematics of the same state) in the order declared; q and v are the whole state, but the function must read only what it
 * declared (the partial derivatives, and what the model evaluates for it, cover only that). */
typedef struct ap_state_args {
  double t;
  const double *x;         /* nx declared inputs */
  int nx;
  const double *q, *v;     /* n coordinates, k speeds */
} ap_state_args;

/* A scalar F(t, x) of time and the declared inputs: write *f. When df is not NULL also write
 * the exact partial derivatives df[0] = dF/dt and df[1 + i] = dF/dx_i (i < nx): they are what
 * a linearization needs (a C function of doubles cannot be differentiated from outside; the
 * scene layer fills them from its Taylor jets, a C user by hand), and what
 * ap_body_actuator_partials returns through the chain rule. df is NULL in ordinary evaluations.
 * Return codes as ap_time_fn. */
typedef int (*ap_state_fn)(const ap_state_args *a, double *f, double *df, void *user);

/* ------------------------------------------------------------------------------------------ */
/* Bodies and shapes.                                                                          */

/* Convex shapes, centred at the body origin with their symmetry axis along body z. Only the
 * plane-contact joint uses the shape (its support function sigma gives the height). */
typedef enum ap_shape_kind {
  AP_SHAPE_NONE = 0,       /* no shape (default) */
  AP_SHAPE_POINT = 1,      /* the body origin itself */
  AP_SHAPE_SPHERE = 2,     /* radius */
  AP_SHAPE_ELLIPSOID = 3,  /* semi_axes along body x, y, z */
  AP_SHAPE_DISK = 4,       /* thin disk of radius `radius` in the body xy plane */
  AP_SHAPE_TORUS = 5       /* wheel with a rounded rim: tube of radius `tube` around the circle of
                              radius `radius` in the body xy plane */
} ap_shape_kind;

typedef struct ap_shape {
  ap_shape_kind kind;      /* default AP_SHAPE_NONE */
  double radius;           /* sphere, disk, torus (m); default 0 */
  double tube;             /* torus tube radius (m); default 0 */
  double semi_axes[3];     /* ellipsoid (m); default 0 */
  double flat_tol;         /* disk, torus: lying flat (|sin| of the axis tilt from the vertical
                              below flat_tol) is reported as an error; default 1e-6 */
} ap_shape;

typedef struct ap_body_def {
  const char *name;        /* used in coordinate names and messages; default "body<id>" */
  double mass;             /* kg, > 0; default 1 */
  double com[3];           /* centre of mass in body axes (m); default 0 */
  double inertia[9];       /* inertia tensor about the centre of mass in body axes (kg m^2),
                              3 x 3 column-major, symmetric positive definite; default 0 (must
                              be set, or filled by ap_body_def_uniform) */
  ap_shape shape;          /* default none */
  int internal_check;       /* set by ap_body_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_body_def;

AP_API ap_body_def ap_body_def_default(void);
/* Set mass and the inertia of a uniform solid of def->shape (disk: a thin lamina) about its
 * centre, and put the centre of mass at the body origin. AP_ERR_ARG for a NULL def, a point,
 * no shape or an unknown kind, or a mass that is not positive and finite. */
AP_API int ap_body_def_uniform(ap_body_def *def, double mass);

/* ------------------------------------------------------------------------------------------ */
/* Joints.                                                                                     */

/* Coordinates (q) and speeds (v) of each kind, with q' = N v:
 *   FIXED          none
 *   REVOLUTE       angle about axis                  ; its rate                      (1, 1)
 *   PRISMATIC      displacement along axis           ; its rate                      (1, 1)
 *   PLANAR         x, y, heading in the parent frame's xy plane ; their rates        (3, 3)
 *   BALL           quaternion [w x y z]               ; angular velocity wx, wy, wz   (4, 3)
 *   FREE           x, y, z, quaternion                ; vx, vy, vz, wx, wy, wz        (7, 6)
 *   PLANE_CONTACT  x, y, quaternion                   ; vx, vy, wx, wy, wz            (6, 5)
 * Rates and velocities are in the parent joint frame's axes (world axes for joints to the
 * ground). The angular velocity is the child's relative to the parent; the quaternion maps the
 * child joint frame to the parent joint frame.
 * PLANE_CONTACT: a convex body resting on the ground plane z = 0. (x, y) is the horizontal
 * position of the body origin (the shape centre); its height is z = sigma(-R^T e_z), sigma the
 * shape's support function, and the contact point is grad sigma(-R^T e_z) in body axes. Its
 * parent must be AP_GROUND and its frames must stay at their defaults. */
typedef enum ap_joint_kind {
  AP_JOINT_FREE = 0,       /* default */
  AP_JOINT_FIXED = 1,
  AP_JOINT_REVOLUTE = 2,
  AP_JOINT_PRISMATIC = 3,
  AP_JOINT_PLANAR = 4,
  AP_JOINT_BALL = 5,
  AP_JOINT_PLANE_CONTACT = 6
} ap_joint_kind;

/* A frame fixed on a body (or the world): origin in body axes (m) and orientation. */
typedef struct ap_frame {
  double pos[3];           /* default 0 */
  double quat[4];          /* [w x y z], normalized at compile; default [1 0 0 0] */
} ap_frame;

typedef struct ap_joint_def {
  const char *name;        /* for messages; default "joint<id>" */
  ap_joint_kind kind;      /* default AP_JOINT_FREE */
  int parent;              /* body id or AP_GROUND (default) */
  int child;               /* body id; required */
  ap_frame parent_frame;   /* joint frame on the parent (world frame for the ground) */
  ap_frame child_frame;    /* joint frame on the child; the joint moves it relative to the
                              parent frame */
  double axis[3];          /* revolute and prismatic axis in the parent joint frame; default
                              (0, 0, 1); normalized at compile */
  /* Driven coordinates: drive[i] != NULL prescribes scalar coordinate i of the joint as a
   * function of time (value, rate, acceleration). The coordinate and its speed are then
   * eliminated from q and v (the system becomes rheonomic; their motion enters the bias h and
   * the free terms a0). Drivable: revolute and prismatic 0; planar 0..2; free 0..2 (position);
   * plane contact 0..1 (x, y). Quaternions cannot be driven (use a prescribed-speed constraint
   * on the angular velocity instead). */
  ap_time_fn drive[3];
  void *drive_user[3];
  int internal_check;       /* set by ap_joint_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_joint_def;

AP_API ap_joint_def ap_joint_def_default(void);

/* ------------------------------------------------------------------------------------------ */
/* Constraints: rows of A v + a0 = 0.                                                          */

typedef enum ap_constraint_kind {
  AP_CON_ROLLING = 0,      /* the material contact point of the body's shape with the ground
                              plane has no horizontal velocity relative to the ground surface
                              (rows .x, .y); with no_spin a row .spin: no angular velocity
                              about the vertical relative to the ground. On a PLANE_CONTACT
                              joint the joint keeps the shape on the plane; on any other joint
                              (a wheel on a revolute joint of a chassis, a free body) the
                              constraint adds the contact row .z: the shape's lowest point
                              stays on z = 0 (an implicit holonomic row, like a loop closure).
                              Shapes: sphere, ellipsoid, disk, torus (and point) */
  AP_CON_KNIFE_EDGE = 1,   /* wheel == 0: the body point `point` has no velocity (relative to
                              the ground surface) along the body-fixed `direction` (1 row).
                              wheel == 1: a wheel's knife edge: the contact point of the body's
                              disk or torus has no velocity across the wheel plane (along the
                              body z axis) (row .side), plus the contact row .z unless the body
                              is on a PLANE_CONTACT joint */
  AP_CON_PRESCRIBED_SPEED = 2, /* speed `speed` of joint `joint` equals f(t) (1 row) */
  AP_CON_USER = 3,         /* `rows` rows from user callbacks */
  AP_CON_COINCIDENT = 4,   /* loop closure: point of body equals point2 of body2, along the
                              world axes selected by `axes` (up to 3 rows .x .y .z) */
  AP_CON_POINT_ON_LINE = 5,  /* loop closure: point of body lies on the line through point2 of
                                body2 along `direction` (body2 axes) (2 rows .n1 .n2) */
  AP_CON_POINT_ON_PLANE = 6  /* loop closure: point of body lies on the plane through point2 of
                                body2 with normal `direction` (body2 axes) (1 row) */
} ap_constraint_kind;

/* The ground surface and how it moves (rolling and knife edge only). The surface is the plane
 * normal . p = offset (z = 0 by default); a moving ground is horizontal, with the surface
 * velocity at the world point p  V(t) + Omega(t) e_z x (p - center). */
typedef enum ap_ground_kind {
  AP_GROUND_FIXED = 0,     /* default */
  AP_GROUND_TURNTABLE = 1, /* rotates about the vertical through (center, 0) at Omega(t) */
  AP_GROUND_TRANSLATING = 2 /* translates horizontally with velocity V(t) */
} ap_ground_kind;

typedef struct ap_ground_motion {
  ap_ground_kind kind;     /* default AP_GROUND_FIXED */
  double center[2];        /* turntable axis (m); default 0 */
  double omega;            /* turntable rate (rad/s) when omega_fn is NULL; default 0 */
  ap_time_fn omega_fn;     /* Omega(t): f[0] = Omega, f[1] = dOmega/dt; default NULL */
  double velocity[2];      /* plane velocity (m/s) when velocity_fn is NULL; default 0 */
  ap_time_fn velocity_fn[2]; /* V_x(t), V_y(t): f[0] velocity, f[1] acceleration */
  void *user;              /* passed to omega_fn and velocity_fn */
  double normal[3];        /* the ground plane's unit normal (world; normalized at compile),
                              pointing out of the ground; default (0, 0, 0), meaning (0, 0, 1).
                              A plane other than z = 0 (an incline) needs a fixed ground and a
                              body that is not on a plane-contact joint (a free body, a wheel) */
  double offset;           /* the plane normal . p = offset (m); default 0 */
  double sphere_radius;    /* > 0: the ground is instead the fixed sphere of this radius (m)
                              about sphere_center, rolled on from outside (a dome) or, with
                              inside = 1, from inside (a bowl); a sphere-shaped body that is not
                              on a plane-contact joint, rolling; default 0 (a plane) */
  double sphere_center[3]; /* (m, world); default 0 */
  int inside;              /* 1: roll inside the sphere; default 0 */
  ap_height_fn height_fn;  /* non-NULL: the ground is instead the fixed height field
                              z = h(x, y), rolled on by a body that is not on a plane-contact
                              joint (rolling or the wheel knife edge; no friction modes); the
                              contact point is the closest point, found by Newton; default NULL */
  void *height_user;       /* passed to height_fn; default NULL */
} ap_ground_motion;

typedef struct ap_constraint_def {
  const char *name;        /* row names are name, or name.x ...; default "constraint<id>" */
  ap_constraint_kind kind; /* default AP_CON_ROLLING */
  int body;                /* rolling, knife edge; loops: the body carrying `point` */
  int no_spin;             /* rolling: add the no-spin row; default 0 */
  ap_ground_motion ground; /* rolling, knife edge */
  double point[3];         /* knife edge, loops: point in body axes (m); default 0 */
  double direction[3];     /* knife edge: body axes; line direction or plane normal: body2 axes;
                              default (0, 1, 0) */
  int wheel;               /* knife edge: 1 = at the contact point of the body's disk or torus,
                              across the wheel plane (point and direction unused); default 0 */
  int body2;               /* loops: the other body or AP_GROUND (default) */
  double point2[3];        /* loops: point in body2 axes (world for AP_GROUND) (m) */
  unsigned axes;           /* coincident: world axes kept, bit 0 = x, 1 = y, 2 = z; default 7 */
  int joint;               /* prescribed speed: the joint */
  int speed;               /* prescribed speed: index of the speed within the joint; default 0 */
  double speed_value;      /* prescribed speed: f(t) = speed_value when speed_fn is NULL */
  ap_time_fn speed_fn;     /* prescribed speed: f(t), f'(t) */
  int rows;                /* user: number of rows */
  ap_constraint_fn user_constraint; /* user: A (rows x k, ld rows) and a0 (rows) */
  ap_gamma_fn user_gamma;  /* user: gamma = -(A' v + a0') (rows) */
  void *user;              /* passed to speed_fn and the user callbacks */
  double mu;               /* rolling on a body not on a plane-contact joint: the friction
                              coefficient of the contact modes (docs/scenes.md "Friction,
                              slip and lift-off"): the contact sticks while |F_t| <= mu F_n
                              and slides otherwise; default -1: none (perfectly rough, as
                              without contact modes) */
  double mu_kinetic;       /* sliding friction coefficient (Coulomb, -mu_kinetic F_n s/|s|);
                              default -1: mu */
  int unilateral;          /* 1: the contact lifts off when F_n falls through 0 and touches
                              down when the gap closes (a sticking plastic impact); 0: it
                              holds (bilateral); default -1: 1 when mu >= 0, else 0 */
  double restitution;      /* unilateral contacts: coefficient of restitution e of the normal
                              part of the touchdown impact, 0 <= e <= 1 (the contact point
                              leaves at e times its closing speed; the tangential part
                              sticks); default 0: plastic */
  int internal_check;       /* set by ap_constraint_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_constraint_def;

AP_API ap_constraint_def ap_constraint_def_default(void);

/* ------------------------------------------------------------------------------------------ */
/* Effects: contributions to Q. Only the effects added are evaluated.                          */

typedef enum ap_effect_kind {
  AP_EFFECT_GRAVITY = 0,   /* uniform field `gravity` on every body (default) */
  AP_EFFECT_SPRING = 1,    /* spring-damper between point of body and point2 of body2:
                              tension f = stiffness (L - rest_length) + damping L'; with
                              rest_length 0 the force is the vector stiffness d + damping d' */
  AP_EFFECT_JOINT_DAMPING = 2, /* generalized force -damping v_i on every speed of `joint` */
  AP_EFFECT_APPLIED = 3,   /* force and torque (world axes) at `point` of `body`: the constants
                              force, torque, or wrench(t) when given */
  AP_EFFECT_USER = 4,      /* user callback adding to Q (k entries) */
  AP_EFFECT_JOINT_FORCE = 5, /* generalized force tau on speed `speed` of `joint`: Q_i += tau, a
                              torque (N m) on an angular speed, a force (N) on a linear one,
                              acting on the child and reacting on the parent along the joint's
                              motion (its power is tau v_i). tau = state_fn(t, x) when given,
                              else value_fn(t) f[0] when given, else `value` */
  AP_EFFECT_MOTOR = 6      /* PD motor on speed `speed` of `joint` with set-point s = state_fn,
                              value_fn or value as above:
                                AP_MOTOR_RATE   tau = kd (s - v_i)
                                AP_MOTOR_ANGLE  tau = kp (s - q_i) + kd (s' - v_i), q_i the
                                                joint coordinate whose rate is v_i; s' = f[1] of
                                                value_fn, 0 otherwise
                              then |tau| <= max_effort (saturated: tau = +-max_effort); Q_i += tau
                              as for AP_EFFECT_JOINT_FORCE */
} ap_effect_kind;

typedef enum ap_motor_mode {
  AP_MOTOR_RATE = 0,       /* holds the speed at the set-point (rad/s or m/s) (default) */
  AP_MOTOR_ANGLE = 1       /* holds the coordinate at the set-point (rad or m): revolute,
                              prismatic, planar x y heading, free x y z, plane contact x y */
} ap_motor_mode;

typedef struct ap_effect_def {
  const char *name;        /* default "effect<id>" */
  ap_effect_kind kind;     /* default AP_EFFECT_GRAVITY */
  double gravity[3];       /* m/s^2; default (0, 0, -9.81) */
  int body;                /* spring end A, applied body */
  int body2;               /* spring end B; AP_GROUND (default) */
  double point[3];         /* body axes (m) */
  double point2[3];        /* body2 axes, world for the ground (m) */
  double stiffness;        /* N/m, >= 0 */
  double damping;          /* spring: N s/m; joint damping: N s/m or N m s/rad; >= 0 */
  double rest_length;      /* m, >= 0 */
  int joint;               /* joint damping */
  double force[3];         /* applied (N) */
  double torque[3];        /* applied (N m) */
  ap_wrench_fn wrench;     /* applied: overrides force and torque when given */
  ap_force_fn generalized; /* user: add to Q (the array holds the other effects' sum) */
  /* Joint forces and motors. The speed must not be driven. */
  int speed;               /* local index of the speed within `joint`; default 0 */
  double value;            /* joint force: tau (N m or N); motor: set-point; default 0 */
  ap_time_fn value_fn;     /* tau or set-point as f[0] of a function of time; default NULL */
  ap_state_fn state_fn;    /* tau or set-point as a function of the state (wins over
                              value_fn); default NULL */
  int ninputs;             /* state_fn: how many inputs it reads, <= AP_STATE_MAX_INPUTS */
  ap_state_input inputs[AP_STATE_MAX_INPUTS]; /* state_fn: what it reads, in the order of x */
  ap_motor_mode motor;     /* default AP_MOTOR_RATE */
  double kp;               /* motor, AP_MOTOR_ANGLE: N m/rad or N/m, >= 0; default 0 */
  double kd;               /* motor: N m s/rad or N s/m, >= 0; default 0 (a rate motor needs
                              kd > 0) */
  double max_effort;       /* motor: |tau| <= max_effort (N m or N), > 0; default HUGE_VAL (no
                              limit) */
  void *user;              /* passed to wrench, generalized, value_fn and state_fn */
  int internal_check;       /* set by ap_effect_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_effect_def;

AP_API ap_effect_def ap_effect_def_default(void);

/* ------------------------------------------------------------------------------------------ */
/* The builder.                                                                                */

typedef struct ap_builder ap_builder;

/* name may be NULL ("bodies"); AP_ERR_ARG when out is NULL. */
AP_API int ap_builder_create(const char *name, ap_builder **out);
AP_API void ap_builder_free(ap_builder *b);   /* NULL: nothing */
/* Add an element; *id (may be NULL) receives its id. Definitions are copied (names too);
 * user pointers are kept. Validation happens in ap_builder_compile. AP_ERR_ARG when b or def
 * is NULL, and (with the message "ap_joint_def 'x' was not made by ap_joint_def_default()")
 * when def was not made by its *_default() function. */
AP_API int ap_builder_add_body(ap_builder *b, const ap_body_def *def, int *id);
AP_API int ap_builder_add_joint(ap_builder *b, const ap_joint_def *def, int *id);
AP_API int ap_builder_add_constraint(ap_builder *b, const ap_constraint_def *def, int *id);
AP_API int ap_builder_add_effect(ap_builder *b, const ap_effect_def *def, int *id);
/* The evaluation path ap_builder_compile chooses (system.h, ap_path; default AP_PATH_AUTO).
 * AP_PATH_TREE on a model the tree path cannot take makes the compile fail with
 * AP_ERR_UNSUPPORTED and the reason (the constraint that joins bodies). AP_ERR_ARG for NULL b
 * or an unknown path. */
AP_API int ap_builder_set_path(ap_builder *b, ap_path path);
/* Validate and compile. On failure *out is NULL, the status is AP_ERR_ARG (or AP_ERR_NOMEM)
 * and ap_builder_message names the element and the offending number (ids and kinds out of
 * range included). AP_ERR_ARG when b or out is NULL. The builder may be compiled again or
 * freed; the model does not refer to it. */
AP_API int ap_builder_compile(ap_builder *b, ap_model **out);
AP_API const char *ap_builder_message(const ap_builder *b);   /* "" when b is NULL */

/* ------------------------------------------------------------------------------------------ */
/* Queries on a compiled body model (AP_ERR_ARG for a NULL or math-level model, bad ids, NULL  */
/* required pointers, or a data struct made for another model).                              */

AP_API int ap_model_is_body_model(const ap_model *m);   /* 0 for NULL */
AP_API int ap_model_body_count(const ap_model *m);
/* -1 if none (or m or name is NULL). */
AP_API int ap_model_find_body(const ap_model *m, const char *name);
AP_API int ap_model_find_coord(const ap_model *m, const char *name);
AP_API int ap_model_find_speed(const ap_model *m, const char *name);
/* Body b's name (NULL for a bad id or a math-level model) and shape (AP_ERR_ARG likewise, or for
 * a NULL out); ids in the order of creation. */
AP_API const char *ap_model_body_name(const ap_model *m, int b);
AP_API int ap_model_body_shape(const ap_model *m, int b, ap_shape *out);
/* Index in q (v) of the joint's first free coordinate (speed); -1 when it has none. */
AP_API int ap_joint_coord_index(const ap_model *m, int joint);
AP_API int ap_joint_speed_index(const ap_model *m, int joint);
/* First row of the constraint in A. */
AP_API int ap_constraint_row_index(const ap_model *m, int constraint);
/* The ground surface of constraint c (a rolling or knife-edge constraint) as compiled, for
 * drawing it: normal is the plane's unit normal ((0, 0, 1) for z = 0) and offset its
 * normal . p, or sphere_radius > 0 with sphere_center and inside for a ground sphere, or
 * height_fn (non-NULL, with height_user) for a height field; kind and the motion fields as
 * defined. AP_ERR_ARG for a math-level model, a bad c or a NULL out;
 * AP_ERR_UNSUPPORTED for a constraint of another kind (it has no ground). */
AP_API int ap_model_constraint_ground(const ap_model *m, int c, ap_ground_motion *out);

/* Kinematics at the data's (t, q, v) into its scratch, without any solve. The state queries
 * below read what the last ap_body_eval or pipeline run (ap_forward, ap_sim_advance) left. */
AP_API int ap_body_eval(const ap_model *m, ap_data *d);

typedef struct ap_body_state {
  double pos[3];           /* body origin (m) */
  double R[9];             /* body axes in world axes (column-major) */
  double com[3];           /* centre of mass (m) */
  double omega[3];         /* angular velocity (rad/s) */
  double vel[3];           /* velocity of the centre of mass (m/s) */
  int has_contact;         /* body on a plane-contact joint or held by a wheel contact */
  double contact[3];       /* its contact point: the lowest point of its shape (m) */
} ap_body_state;

AP_API int ap_body_get_state(const ap_model *m, const ap_data *d, int body, ap_body_state *out);
/* Quantity `which` (ap_body_qty) of body `body` from what the last ap_body_eval or pipeline run
 * left, into *value. AP_ERR_ARG for a bad id or quantity or a NULL value. */
AP_API int ap_body_quantity(const ap_model *m, const ap_data *d, int body, int which,
                            double *value);
/* Jacobians of a body point p (body axes): angular Jw and linear Jv (each 3 x k, ld 3) with
 * w = Jw v + rw, v_p = Jv v + rv (rw, rv: rheonomic parts from driven coordinates), and the
 * bias accelerations aw = Jw' v + rw', av = Jv' v + rv' (after a velocity stage). Any output
 * may be NULL. */
AP_API int ap_body_point_jacobian(const ap_model *m, const ap_data *d, int body,
                                  const double p[3], double *Jw, double *Jv, double rw[3],
                                  double rv[3], double aw[3], double av[3]);
/* Kinetic energy (from the full body velocities) and potential energy of the gravity and
 * spring effects at the data's (t, q, v). Evaluates the kinematics itself. */
AP_API int ap_body_energy(const ap_model *m, ap_data *d, double *kinetic, double *potential);
/* How many times effect `effect` was evaluated with this data; -1 for bad arguments. */
AP_API long ap_body_effect_count(const ap_model *m, const ap_data *d, int effect);
/* A joint force or motor effect at the data's (t, q, v): it adds *tau to Q[*col]. The exact
 * partial derivatives of tau (each output may be NULL): dtau_dq (n entries), dtau_dv (k),
 * dtau_dt, from the state function's df (it is called with df), the value function's f[1] and
 * f[2] and the PD law; while the motor saturates they are zero. Runs no kinematics (these effects
 * read q and v only). AP_ERR_UNSUPPORTED, with the message, for a state function that reads a
 * body quantity (AP_STATE_BODY): its partials reach a linearization through the complex-step
 * evaluation instead. AP_ERR_ARG for another kind of effect; a failing callback's code. */
AP_API int ap_body_actuator_partials(const ap_model *m, ap_data *d, int effect, int *col,
                                     double *tau, double *dtau_dq, double *dtau_dv,
                                     double *dtau_dt);
/* Put q on its manifold: unit quaternions and loop closures (Gauss-Newton, minimum-norm
 * steps) at time d->t. *change (may be NULL) receives the size of the correction. The
 * drivers call the same after each accepted step; call it to assemble an initial state. */
AP_API int ap_body_project_q(const ap_model *m, ap_data *d, double *q, double *change);
/* Largest |phi(q, t)| of the loop-closure constraints (m) at the data's (t, q); 0 when the
 * model has none. The minimal, projected and plain drivers keep it below 1e-12 x the model's
 * length scale (ap_body_project_q after each step); the DAE mode does not project q. */
AP_API int ap_body_loop_residual(const ap_model *m, ap_data *d, double *phi_max);
/* Complete speeds: keep v[i] where given[i] != 0 and set the others (minimum norm) so that
 * A v + a0 = 0 at (d->t, q). AP_ERR_INCONSISTENT when that leaves a residual. */
AP_API int ap_body_complete_speeds(const ap_model *m, ap_data *d, const double *q,
                                   const int *given, double *v);

/* How a contact's normal force is known (ap_contact_force.load). */
typedef enum ap_load_kind {
  AP_LOAD_UNIQUE = 0,     /* determined by the motion: a plane-contact body's Newton's law, or a
                             wheel's share of its chassis' vertical reaction and tilting moments
                             with at most three non-collinear contacts under the chassis */
  AP_LOAD_MIN_NORM = 1,   /* statically indeterminate (four or more rigid contacts under one
                             chassis, or three on a line...): the minimum-norm distribution, one
                             of many that hold the chassis; a suspension makes it unique */
  AP_LOAD_JOINT = 2       /* under a planar chassis joint with fewer than three non-collinear
                             contacts: the wheels carry the vertical force and the moment they
                             can; the joint keeps the tilting moment about their line (a
                             two-wheeled robot without a caster would tip over) */
} ap_load_kind;

/* The contact force of a rolling constraint (AP_CON_ROLLING): the force of the ground on the
 * body at the contact point, world axes. The tangential part is the friction the rolling rows
 * need (their multipliers). The normal part: a body on a plane-contact joint carries it
 * through the joint, which has no multiplier for it, so it comes from Newton's law for the
 * vertical over the body and its descendants (F_n = sum m_b a_b,z minus the effects' and the
 * other constraints' vertical forces on them). A wheel (a rolling body on any other joint)
 * shares with the other wheels under the same chassis (the nearest ancestor joined to the
 * ground) the vertical force and the tilting moments that hold the chassis: on a free chassis
 * those are the wheels' contact rows, on a planar chassis the joint's vertical reaction and
 * roll and pitch moments, which the wheels carry in reality; both forms give the same loads
 * (docs/vehicles.md "Wheel loads"). */
typedef struct ap_contact_force {
  double point[3];         /* contact point on the ground (m) */
  double force[3];         /* ground on body (N), world axes: x, y tangential, z = normal on the
                              plane z = 0; on a tilted plane (ap_ground_motion.normal) the sum
                              of the tangential and normal parts */
  double normal;           /* F_n (N) along the ground's normal (force[2] on z = 0); negative:
                              the ground would have to pull */
  double tangential;       /* |F_t| (N) */
  double friction_ratio;   /* |F_t| / F_n: the least friction coefficient a real surface needs
                              for rolling without slip; HUGE_VAL when F_n <= 0 */
  double spin_torque;      /* no-spin row: the ground's torque about the vertical (N m); 0
                              without it */
  int lift_off;            /* 1 when F_n < 0: the body would lift off (the model keeps it on
                              the plane regardless) */
  ap_load_kind load;       /* how F_n is known; AP_LOAD_UNIQUE for a plane-contact body (unless
                              loops join it to a planar chassis: then its vehicle's share) */
  int ncontacts;           /* wheels: the contacts sharing the chassis' load (1 otherwise) */
} ap_contact_force;

/* The contact force of rolling constraint `constraint` at the data's pipeline state: the
 * kinematics and v' of the last ap_forward at (t, q, v) (ap_sim_data after ap_sim_create or
 * ap_sim_advance has them), and the multipliers lambda (b entries; NULL means d->lambda, e.g.
 * after ap_fwd_reactions). With a simulation pass ap_sim_reactions' lambda: in DAE mode those
 * are IDA's own. AP_ERR_ARG for a math-level model, a bad id or another constraint kind;
 * AP_ERR_UNSUPPORTED when the model has a user effect or a user constraint (their generalized
 * forces cannot be attributed to bodies); AP_ERR_CALLBACK when a wrench callback fails.
 * d is only read: any number of threads may query one data at once. On the tree path the call
 * allocates its own 6 x (bodies) doubles for the twists of v' (AP_ERR_NOMEM when it cannot). */
AP_API int ap_body_contact_force(const ap_model *m, const ap_data *d, const double *lambda,
                                 int constraint, ap_contact_force *out);

/* Quaternion helpers ([w x y z]). Nothing is written when an argument is NULL. */
AP_API void ap_quat_from_axis_angle(const double axis[3], double angle, double q[4]);
AP_API void ap_quat_mul(const double a[4], const double b[4], double out[4]);
AP_API void ap_quat_to_matrix(const double q[4], double R[9]);
AP_API void ap_quat_from_matrix(const double R[9], double q[4]);

/* Contact modes (rolling constraints with mu >= 0 or unilateral; docs/scenes.md "Friction,
 * slip and lift-off"): set the mode of each such contact in d from the state (d->t and d->q
 * set, v the speeds or NULL): airborne when unilateral and its gap exceeds tol (m), else sliding when it has a friction
 * coefficient and v makes its contact point slip faster than tol (1 + max |v_i|) (m/s), else
 * rolling. The modes then shape every evaluation with d (rows dropped, friction); simulations
 * choose them so at creation. Returns the number of contacts set sliding or airborne (0: all
 * roll, or the model has no contact modes), or AP_ERR_ARG (m not a body model, d not made for
 * m, tol not positive) or a failure of the position stage. */
AP_API int ap_body_contact_modes(const ap_model *m, ap_data *d, const double *v, double tol);

#ifdef __cplusplus
}
#endif
#endif
