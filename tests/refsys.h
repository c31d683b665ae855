/* Reference systems with known answers (docs/references.md), written by hand as math-level systems.
 *
 * Each problem gives: a parameter struct, rs_<problem>_system() filling an ap_system_def with
 * callbacks whose user pointer is the parameter struct (which must outlive the model), the exact
 * solution at time t from an initial state at t = 0, and its invariants. The callbacks return
 * exactly the founding paper's objects (docs/design.md §1): metric g (k x k, column-major), bias h
 * or the metric derivative dg/dq, forces Q, constraint rows A (b x k, column-major), free term
 * a0 and gamma = -(A' v + a0') as the total time derivative along the motion at fixed v.
 *
 * Shared by tests/test_reference.c, examples/ and bench/ through refsys_dep. */
#ifndef AP_TESTS_REFSYS_H
#define AP_TESTS_REFSYS_H

#include <appell/appell.h>

/* pi to double precision (M_PI is not ISO C). */
#define RS_PI 3.14159265358979323846

/* ------------------------------------------------------------------------------------------ */
/* 1. Knife edge (skate) on an inclined plane. docs/references.md §1.                             */
/* q = (x, y, phi), v = q'; g = diag(m, m, J); Q = (m grav sin(alpha), 0, 0); h = 0;           */
/* A = [sin phi, -cos phi, 0], a0 = 0. Needs w0 != 0 for the closed form.                     */

typedef struct rs_knife {
  double m;       /* mass (kg) */
  double J;       /* inertia about the plane normal through the contact point (kg m^2) */
  double grav;    /* gravity (m/s^2) */
  double alpha;   /* slope of the plane (rad); x points down the slope */
} rs_knife;

void rs_knife_system(rs_knife *p, ap_system_def *def);
/* Initial (q0, v0) from position, heading, speed along the blade u0 and turn rate w0. */
void rs_knife_initial(double x0, double y0, double phi0, double u0, double w0, double q0[3],
                      double v0[3]);
/* Exact state at t from (q0, v0) at 0: q (3), v (3) and the multiplier lambda of the row A
 * (M q'' = Q + A^T lambda). Any output may be NULL. */
void rs_knife_exact(const rs_knife *p, const double q0[3], const double v0[3], double t,
                    double *q, double *v, double *lambda);
/* T + V, V = -m grav x sin(alpha). Conserved. */
double rs_knife_energy(const rs_knife *p, const double *q, const double *v);

/* ------------------------------------------------------------------------------------------ */
/* 2. Chaplygin sleigh. docs/references.md §2. q = (x, y, theta) of the blade contact, v = q'.   */
/* The non-diagonal printed metric; h either from dg/dq (AP_BIAS_CHRISTOFFEL) or from an      */
/* explicit bias callback h = (-m a w^2 cos theta, -m a w^2 sin theta, 0).                     */

typedef struct rs_sleigh {
  double m;       /* mass (kg) */
  double I;       /* inertia about the centre of mass (kg m^2) */
  double a;       /* distance from the contact point to the centre of mass along e1 (m) */
} rs_sleigh;

/* explicit_bias = 0: AP_BIAS_CHRISTOFFEL with metric_deriv; 1: AP_BIAS_CALLBACK. */
void rs_sleigh_system(rs_sleigh *p, int explicit_bias, ap_system_def *def);
void rs_sleigh_initial(double x0, double y0, double theta0, double u0, double w0, double q0[3],
                       double v0[3]);
/* Exact state at t: u, w, theta closed form; x, y by composite Gauss-Legendre quadrature
 * (error below 1e-13 for the parameters used here). q, v may be NULL. */
void rs_sleigh_exact(const rs_sleigh *p, const double q0[3], const double v0[3], double t,
                     double *q, double *v);
/* m u^2 / 2 + J w^2 / 2 (= 1/2 v^T g v on the constraint), J = I + m a^2. Conserved. */
double rs_sleigh_energy(const rs_sleigh *p, const double *q, const double *v);

/* ------------------------------------------------------------------------------------------ */
/* 3. Ball on a rotating turntable. docs/references.md §3. q = (x, y, a1, a2, a3), v = q' =       */
/* (x', y', wx, wy, wz). For a uniform sphere the orientation never enters the dynamics       */
/* (g = diag(m, m, I, I, I) whatever the attitude), so integrating the angular-velocity       */
/* components a' = (wx, wy, wz) as if they were coordinate rates is a valid math-level system;  */
/* the a_i are not rotation angles of the ball. A = [[1,0,0,-R,0],[0,1,R,0,0]],               */
/* a0 = (Omega(t) y, -Omega(t) x), Omega(t) = Omega0 + dOmega t (rheonomic when dOmega != 0).   */

typedef struct rs_turntable {
  double m;       /* mass (kg) */
  double R;       /* radius (m) */
  double kI;      /* I = kI m R^2 (2/5 solid, 2/3 hollow) */
  double Omega0;  /* table rate at t = 0 (rad/s) */
  double dOmega;  /* table angular acceleration (rad/s^2) */
} rs_turntable;

void rs_turntable_system(rs_turntable *p, ap_system_def *def);
double rs_turntable_omega(const rs_turntable *p, double t);
/* Initial (q0, v0) at t = 0: centre (x0, y0), angles 0, spin (wx, wy, wz); (x', y') are set
 * from the no-slip constraint. */
void rs_turntable_initial(const rs_turntable *p, double x0, double y0, double wx, double wy,
                          double wz, double q0[5], double v0[5]);
/* Exact state at t from z'' = i kt (Omega z)', kt = kI/(1+kI): z' = i kt Omega(t) z + c.
 * With dOmega != 0 it uses a Gauss-Legendre quadrature of exp(-i kt int Omega). */
void rs_turntable_exact(const rs_turntable *p, const double q0[5], const double v0[5],
                        double t, double *q, double *v);
/* The conserved complex number c = z' - i kt Omega(t) z as (Re, Im). wz is conserved too. */
void rs_turntable_invariant(const rs_turntable *p, double t, const double *q, const double *v,
                            double c[2]);

/* ------------------------------------------------------------------------------------------ */
/* 4. Particle on a rotating inclined line. docs/references.md §5.                                */
/* (a) reduced: q = r, k = 1, b = 0, g = m, h = -m s^2 r, Q = -m grav cos(alpha), s = w sin a. */
/* (b) 3-D: q = p = (X, Y, Z), g = m I, Q = (0, 0, -m grav); the line imposed as two           */
/*     rheonomic velocity rows n_i . p' + n_i' . p = 0 with                                   */
/*     n1 = (-sin wt, cos wt, 0), n2 = (cos a cos wt, cos a sin wt, -sin a).                   */
/* The line direction is d = (sin a cos wt, sin a sin wt, cos a), r = p . d.                   */

typedef struct rs_line {
  double m;       /* mass (kg) */
  double grav;    /* gravity (m/s^2) */
  double alpha;   /* angle of the line from the vertical (rad) */
  double w;       /* rotation rate about the vertical (rad/s) */
} rs_line;

void rs_line_reduced_system(rs_line *p, ap_system_def *def);
void rs_line_3d_system(rs_line *p, ap_system_def *def);
/* Exact r(t), r'(t) from r0, r0' at t = 0 (s != 0). */
void rs_line_exact(const rs_line *p, double r0, double rd0, double t, double *r, double *rd);
/* Point and velocity in 3-D for (r, r') at time t: p = r d(t), p' = r' d + r d'. */
void rs_line_lift(const rs_line *p, double t, double r, double rd, double q3[3], double v3[3]);
/* Jacobi integral m (r'^2 - s^2 r^2)/2 + m grav r cos(alpha). Conserved. */
double rs_line_jacobi(const rs_line *p, double r, double rd);
/* The same from the 3-D state: E - w L_z. */
double rs_line_jacobi_3d(const rs_line *p, const double *q3, const double *v3);

/* ------------------------------------------------------------------------------------------ */
/* 5. Hoffmann's two-rod pendulum (Kron's method). docs/references.md §6.                         */
/* (a) reduced q = (theta, phi): printed g, Q; h from dg/dq (AP_BIAS_CHRISTOFFEL).             */
/* (b) primitive q = (theta, phi, y, z): M = diag(I1 + m1 a1^2, I2, m2, m2),                   */
/*     forces (-m1 grav a1 sin theta, 0, F, -m2 grav), h = 0, connection as two velocity rows  */
/*     y' - 2 a1 cos theta theta' - a2 cos phi phi' = 0,                                      */
/*     z' - 2 a1 sin theta theta' - a2 sin phi phi' = 0.                                      */

typedef struct rs_hoffmann {
  double m1, m2;  /* rod masses (kg) */
  double a1, a2;  /* half lengths (m) */
  double I1, I2;  /* central inertias (kg m^2) */
  double grav;    /* gravity (m/s^2) */
  double F;       /* horizontal force at the lower rod's midpoint (N) */
} rs_hoffmann;

void rs_hoffmann_reduced_system(rs_hoffmann *p, ap_system_def *def);
void rs_hoffmann_primitive_system(rs_hoffmann *p, ap_system_def *def);
/* The printed g (2 x 2, column-major) and Q (2) at q = (theta, phi). */
void rs_hoffmann_printed(const rs_hoffmann *p, const double q2[2], double g[4], double Q[2]);
/* Kron: C^T M C and C^T F of the primitive system with the connection Jacobian C (4 x 2). */
void rs_hoffmann_connected(const rs_hoffmann *p, const double q2[2], double g[4], double Q[2]);
/* Primitive state (q4, v4) from the reduced (q2, v2) through the connection. */
void rs_hoffmann_lift(const rs_hoffmann *p, const double q2[2], const double v2[2],
                      double q4[4], double v4[4]);
/* Energy with the constant force's potential -F y: 1/2 v^T g v - (m1 + 2 m2) grav a1 cos theta
 * - m2 grav a2 cos phi - F (2 a1 sin theta + a2 sin phi). Conserved. Reduced state. */
double rs_hoffmann_energy(const rs_hoffmann *p, const double q2[2], const double v2[2]);
/* The equilibrium under constant F: tan theta* = 2F/((m1 + 2 m2) grav), tan phi* = F/(m2 grav). */
void rs_hoffmann_equilibrium(const rs_hoffmann *p, double q2[2]);

/* ------------------------------------------------------------------------------------------ */
/* Helpers. */

/* Nodes and weights of the n-point Gauss-Legendre rule on [-1, 1] (n <= 64). */
void rs_gauss_legendre(int n, double *x, double *w);
/* Largest |A v + a0| of a system's constraint callback at (t, q, v), and the round-off scale
 * max_i (sum_j |A_ij v_j| + |a0_i|) in *scale (may be NULL). Returns -1 on callback failure.
 * b, k <= 16. */
double rs_residual(const ap_system_def *def, double t, const double *q, const double *v,
                   double *scale);

#endif
