/* Body models shared by the tests and the benchmarks: each problem built from bodies, joints,
 * constraints and effects through the public builder API (appell/body.h), and the helpers
 * that put it in a given state.
 *
 *   rolling disk / torus   plane-contact joint + rolling (optional no-spin row, applied lift)
 *   heavy symmetric top    ball joint at the pivot, gravity
 *   rattleback             ellipsoid with skewed inertia and a low centre of mass, rolling
 *   ball on a turntable    sphere on the plane-contact joint rolling on a turning ground
 *   skate on an incline    planar joint on an inclined frame + knife edge + gravity
 *   Chaplygin sleigh       planar joint, centre of mass ahead of the blade + knife edge
 *   Hoffmann's pendulum    two rods: a tree of revolutes (optionally its lower end sliding on
 *                          a vertical line) or the primitive revolute + planar + hinge rows
 *
 * The skate, sleigh, turntable and Hoffmann models are the body twins of the math-level
 * reference systems of tests/refsys.h and take the same parameter structs.
 *
 * Failures: a function that cannot build or set its problem prints what failed (with the
 * library's message) to stderr, counts it in bs_failures() and returns NULL (models) or the
 * status (states). Tests end with AP_CHECK_EQ_INT(bs_failures(), 0); benchmarks stop. */
#ifndef AP_TESTS_BODYSYS_H
#define AP_TESTS_BODYSYS_H

#include <appell/appell.h>

#include "refsys.h"

/* Number of failures reported by the functions below since the program started. */
int bs_failures(void);

/* Compiles the builder and frees it; NULL (failure counted) when it does not compile. */
ap_model *bs_compile(ap_builder *b);

/* A body with mass, centre of mass com (NULL: origin) and inertia diag(Idiag) about it; its
 * id, or -1 (failure counted). */
int bs_add_body(ap_builder *b, const char *name, double mass, const double *com,
                const double *Idiag);

/* ap_sim_create at t0 = 0 with mode, method, rtol and atol; NULL (failure counted, message
 * printed) when it refuses. */
ap_sim *bs_start(const ap_model *m, ap_mode mode, const char *method, double rtol,
                 double atol, const double *q0, const double *v0);

/* A ball (body "ball", a uniform solid of the shape, radius (m), mass (kg)) on a free joint
 * with the contact c (its body set to the ball) and gravity g (m/s^2); NULL (failure counted)
 * when it does not build. */
ap_model *bs_free_ball(ap_shape_kind shape, double radius, double mass,
                       const ap_constraint_def *c, const double *g);
/* bs_free_ball with the effect extra (a user effect, say) added after the gravity. */
ap_model *bs_free_ball_effect(ap_shape_kind shape, double radius, double mass,
                              const ap_constraint_def *c, const double *g,
                              const ap_effect_def *extra);

/* The leaning rod of the Painleve tests: a thin uniform ellipsoid (body "rod", semi-axes a =
 * 0.01, 0.01, c = 0.5 m, 1 kg) on a free joint with the contact name (mu) and gravity 9.81 m/s^2
 * along -z. At the tilt th = 45 deg (q = (0, 0, z, cos(-th/2), 0, sin(-th/2), 0)) its centre is
 * h above its lowest point, which is at r = (rx, 0, rz) from the centre; k2 = (a^2 + c^2) / 5
 * (m^2) about a transverse axis. NULL (failure counted) when it does not build. */
typedef struct bs_rod {
  double a, c, th, h, rx, rz, k2;
} bs_rod;
ap_model *bs_leaning_rod(const char *name, double mu, bs_rod *geo);

/* A uniform sphere (body "ball") on the given joint with the contact c (its body set to the
 * ball), which must not compile: the builder's status (AP_OK, failure counted, when it did
 * compile) and its message in msg. */
int bs_ball_refused(ap_joint_kind joint, double radius, double mass, const ap_constraint_def *c,
                    char *msg, size_t len);

/* T + V of a body model at (q, v) (d->t as set by the caller); NaN on failure. */
double bs_energy(const ap_model *m, ap_data *d, const double *q, const double *v);

/* ---- rolling disk ------------------------------------------------------------------------ */

typedef struct bs_disk {
  double m, r, grav;  /* mass (kg), radius (m), gravity (m/s^2) */
  double A, C;        /* inertia about a diameter and about the axis (kg m^2) */
  int torus;          /* a torus of radius r with a 0.02 m tube (body "wheel") instead */
  int no_spin;        /* add the rolling constraint's no-spin row */
  double lift;        /* > 0: an applied force (0, 0, lift) N at the centre */
} bs_disk;

/* m 1.5 kg, r 0.3 m, g 9.81, the thin uniform disk's A = m r^2 / 4, C = m r^2 / 2. */
bs_disk bs_disk_default(void);

/* Model "rolling disk" (body "disk") or "rolling torus" (body "wheel"): q = (x, y, quaternion),
 * v = (vx, vy, w) of the plane-contact joint. */
ap_model *bs_disk_model(const bs_disk *p);

/* State from heading psi, lean th (from upright), spin phase phi, lean rate thd,
 * w_a = w . b_up (b_up the upward unit vector in the disk plane) and w_n = w . a (the axis
 * a = R e_z); the centre at (0.1, -0.2), its velocity completed from the rolling rows at
 * t = 0. d may be NULL (a data struct is made for the call). */
int bs_disk_state(const ap_model *m, ap_data *d, double psi, double th, double phi,
                  double thd, double wa, double wn, double *q, double *v);

/* Steady circular rolling at lean th and precession rate Om: w_a and w_n. */
void bs_disk_steady_rates(const bs_disk *p, double th, double Om, double *wa, double *wn);

/* The steady turn of bs_disk_steady_rates for the disk on a free joint (bs_free_ball with
 * AP_SHAPE_DISK): q (7) = centre at (0.1, -0.2, r cos th), quaternion (heading psi, lean th
 * from upright, the axis a = R e_z to the left and down), v (6) = centre velocity (the contact
 * point at rest), world angular velocity w_a b_up + w_n a. */
void bs_disk_turn_free(const bs_disk *p, double th, double Om, double psi, double *q,
                       double *v);

/* The lean from upright (rad) of a disk state: a_z = -sin(lean). */
double bs_disk_lean(const double *q);

/* The lean th, its rate thd, w_a and w_n of a disk state (the inverse of bs_disk_state). */
void bs_disk_read(const double *q, const double *v, double *th, double *thd, double *wa,
                  double *wn);

/* ---- heavy symmetric top ----------------------------------------------------------------- */

typedef struct bs_top {
  double m, l;        /* mass (kg), pivot to centre of mass along the axis (m) */
  double A0, C;       /* inertia about a transverse axis and the axis, at the centre of mass */
  double grav;        /* gravity (m/s^2) */
} bs_top;

/* m 0.5 kg, l 0.1 m, A0 2e-3, C 3e-3 kg m^2, g 9.81. */
bs_top bs_top_default(void);

/* Model "heavy top": q = quaternion, v = w (world frame), pivot at the origin. */
ap_model *bs_top_model(const bs_top *p);

/* Axis tilted 0.5 rad about x, spinning 50 rad/s about it, plus w += (0.3, 0, 1) rad/s. */
void bs_top_initial(double q[4], double w[3]);

/* ---- rattleback ------------------------------------------------------------------------- */

/* Ellipsoid 0.2 x 0.03 x 0.02 m, 1 kg uniform, centre of mass 1 cm below the centre, the
 * principal axes of inertia turned by skew (rad) about z against the shape's; rolling. */
ap_model *bs_rattleback_model(double skew);

/* Resting on its bottom, rocking at rock (rad/s about y) and spinning at spin (rad/s about z),
 * the centre velocity completed from rolling at t = 0. d may be NULL. */
int bs_rattleback_state(const ap_model *m, ap_data *d, double rock, double spin, double q[6],
                        double v[5]);

/* ---- twins of the reference systems (tests/refsys.h) ------------------------------------- */

/* Sphere of radius p->R, uniform (kI = 2/5), rolling on a table turning at
 * rs_turntable_omega(p, t); p must outlive the model. q = (x, y, quaternion). */
ap_model *bs_turntable_model(rs_turntable *p);
/* A run of the turntable ball m (body model, free = 1: its free coordinates, found by
 * ap_sim_free_coordinates, left out of the error control; their flags into flags (n) when not
 * NULL) or of its hand model (refsys) from (q0, v0), rtol = atol, to 16 s with 10 outputs:
 * the steps, and in *err the largest centre error against the closed form from (qh, vh).
 * -1 when the run fails. */
long bs_turntable_run(const ap_model *m, const rs_turntable *p, const double *q0,
                      const double *v0, const double *qh, const double *vh, const char *method,
                      double rtol, int free_, int *flags, double *err);

/* Planar joint on a plane inclined by p->alpha about y (x down the slope), knife edge across
 * the body's y; q = (x, y, heading) as rs_knife's. */
ap_model *bs_skate_model(const rs_knife *p);
/* The same with blades = 2: the knife edge written twice ("blade", "blade2"), one redundant
 * row; the motion is the skate's. */
ap_model *bs_skate_model_blades(const rs_knife *p, int blades);

/* Planar joint, centre of mass p->a ahead of the blade along the body's x, knife edge. */
ap_model *bs_sleigh_model(const rs_sleigh *p);

/* m1 1, m2 0.8 kg, a1 0.5, a2 0.4 m, central inertias m a^2 / 3, g 9.81, F 2 N. */
rs_hoffmann bs_hoffmann_params(void);

/* Tree: the upper rod on a revolute about x at the origin (theta), the lower rod on a
 * revolute at its end (psi, relative: phi = theta + psi); gravity and, when p->F != 0, the
 * force F along y at the lower rod's centre. With slide, the lower rod's free end slides on
 * the vertical line y = y_line (a point-on-plane loop): model "Hoffmann sliding". */
ap_model *bs_hoffmann_tree(const rs_hoffmann *p, int slide, double y_line);

/* Primitive: the upper rod on a revolute (theta), the lower rod on a planar joint in the
 * world y-z plane (y, z, phi), the hinge as coincident points along y and z (two loop rows). */
ap_model *bs_hoffmann_primitive(const rs_hoffmann *p);
/* The same with hinges = 2: the hinge written twice ("hinge", "hinge2"): two redundant loop
 * rows (velocity rows of A and rows of phi). */
ap_model *bs_hoffmann_primitive_n(const rs_hoffmann *p, int hinges);

/* The primitive model's state (theta, y, z, phi) and rates from the tree's (theta, psi =
 * phi - theta) and theirs: the lower rod's planar coordinates where the hinge closes. */
void bs_hoffmann_primitive_state(const rs_hoffmann *p, double th, double psi, double thd,
                                 double psd, double q[4], double v[4]);

/* The sliding tree assembled from the rough guess (theta, psi) = (0.5, -0.5) by
 * ap_body_project_q (*change: how far it moved, may be NULL), theta' = 1 and psi' completed. */
int bs_hoffmann_sliding_state(const ap_model *m, double q[2], double v[2], double *change);

/* ---- Chaplygin's ball ------------------------------------------------------------------- */

/* A sphere of radius a and mass m whose centre of mass is at its centre but whose principal
 * moments I (body axes) differ, on the plane-contact joint, rolling without slip under
 * gravity: model "Chaplygin ball", q = (x, y, quaternion), v = (vx, vy, w) (world). Exact
 * invariants: the energy, and the angular momentum about the contact point P, as a vector in
 * the world, K = I_G w + m (G - P) x v_G (no moment about P: gravity acts through the centre
 * above P, the reaction at P; and P moves parallel to G). */
ap_model *bs_chaplygin_ball_model(double mass, double a, const double I[3]);

/* Orientation p (normalized here), angular velocity w (world); the centre at (0.2, -0.1), its
 * velocity completed from rolling at t = 0. d may be NULL. */
int bs_chaplygin_ball_state(const ap_model *m, ap_data *d, const double p[4], const double w[3],
                            double q[6], double v[5]);

/* K (world) at (q, v): R I R^T w + m a e_z x v_G. */
void bs_chaplygin_ball_momentum(double mass, double a, const double I[3], const double q[6],
                                const double v[5], double K[3]);

/* The six models of the DAE accuracy table (tests/test_dae_tight.c, bench/dae_accuracy.c), each
 * with its initial state: rolling disk, rattleback, ball on a turntable, Chaplygin's ball,
 * Hoffmann's sliding rod (loop) and hinged rods (primitive, 2 loop rows). A model that cannot be
 * built is NULL (and counted by bs_failures); free each with ap_model_free. */
#define BS_DAE_CASES 6
typedef struct bs_case {
  const char *name;
  ap_model *m;
  double q0[8], v0[8];
} bs_case;
void bs_dae_cases(bs_case c[BS_DAE_CASES]);

#endif
