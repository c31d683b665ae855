/* Finite-difference checks of the body layer along the motion, shared by test_bodies.c and
 * test_wheels.c.
 *
 * At a state (t, q, v) the path q(s) = q + s N(q) v, t(s) = t + s has tangent (q', 1) at
 * s = 0, so along it (v held fixed)
 *   d/ds x_p   = v_p          (point velocity from the Jacobian: J_p v + rheonomic part)
 *   d/ds R R^T = [w]x         (angular velocity)
 *   d/ds w(s)  = aw           (angular bias acceleration Jw' v + rw')
 *   d/ds v_p(s)= av           (point bias acceleration)
 *   d/ds (A v + a0) = -gamma
 *   d/ds V     = -Q . v       (conservative effects, scleronomic models)
 *   d/ds (o + R c_b) = vP     (a body with a contact: the material point at the contact point
 *                              c_b of s = 0, held fixed on the body; vP from its Jacobian)
 *   d/ds z_c   = e_z . vP     (the height of the geometric contact point: the support point
 *                              slides over the surface horizontally only, since H u = 0)
 * The derivative is a Richardson-extrapolated central difference, (4 D(h/2) - D(h)) / 3 with
 * D(h) = (f(h) - f(-h)) / 2h: truncation O(h^4 f^(5)) ~ 1e-12 for h = 1e-3 on these O(1)
 * problems and round-off ~ eps |f| / h ~ 1e-13, so the relative tolerance FD_TOL = 1e-7
 * (relative to max(1, |analytic|)) leaves five orders of margin while any missing term
 * (a factor 2 in a Coriolis term, the contact point moving over the surface) is O(1) wrong. */
#ifndef AP_TESTS_FDCHECK_H
#define AP_TESTS_FDCHECK_H

#include "check.h"
#include "model/model.h"

#define FD_TOL 1e-7
#define RS_PI_ 3.14159265358979323846
#define MAXB 8
#define MAXK 40
#define MAXR 24

/* Random numbers (xorshift64*, fixed seed): uniform in [0, 1) and [-1, 1). */
double urand(void);
double srand1(void);
void rand_vec(double *x, int n, double s);
void rand_quat(double *q);
void rand_frame(ap_frame *f);
/* A random physical inertia: R diag(l) R^T, l in [1, 1.5] * scale (triangle inequality). */
void rand_inertia(double *I, double scale);

/* Time functions for drives, turntables (Omega, Omega'), translating grounds, speeds. */
int f_sine(double t, double f[3], void *user);
int f_omega(double t, double f[3], void *user);
int f_vel(double t, double f[3], void *user);

/* Everything measured at one state (flat array of doubles, so differences apply at once). */
typedef struct meas {
  double x[MAXB][3], R[MAXB][9], w[MAXB][3], vp[MAXB][3], aw[MAXB][3], av[MAXB][3];
  double xm[MAXB][3], vm[MAXB][3], zc[MAXB];   /* contact: material point, its velocity,
                                                  geometric contact height */
  double c[MAXR], gamma[MAXR], QV, V;
} meas;

typedef struct fd_result {
  double vel, omega, alpha, acc, gamma, power, contact;   /* relative errors */
} fd_result;

int measure(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
            meas *out);
/* Richardson-extrapolated derivative of every field along the path with tangent qd. */
int fd_along(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
             const double *qd, double h, meas *der);
/* Compare the analytic quantities at (t, q, v) with finite differences along the motion; a and
 * der (may be NULL) receive the analytic values and the derivatives. */
int fd_check(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
             double h, fd_result *res, meas *a, meas *der);
double err_rel(const double *an, const double *fd, int n);
/* Model `name`: body "wheel" of the shape kind (radius 0.4 m, tube 0.07 m, semi-axes 0.5, 0.3,
 * 0.2 m; 1.3 kg, a random centre of mass and inertia) on a free joint with the contact c (its
 * body set to the wheel) under gravity; NULL (checks failed) when it does not compile. */
ap_model *fd_free_shape(const char *name, int kind, const ap_constraint_def *c);
/* Random state: coordinates (quaternions unit), speeds, time. */
void rand_state(const ap_model *m, double *q, double *v, double *t);
/* fd_check at several random states (disks and tori at least min_flat in |sin| from lying
 * flat); asserts every error below FD_TOL (the power check when check_power) and returns the
 * worst. */
fd_result fd_many(const char *label, const ap_model *m, int samples, int check_power,
                  double min_flat);

#endif
