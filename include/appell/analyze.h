/* Appell: operating points, linearization, eigenvalues and sweeps (docs/linearize.md).
 *
 * A linearizer (ap_lin) is bound to one model. It works on the reduced equations
 *
 *     x = (c_I, u_I),     x' = F(x)
 *
 * where c are chart coordinates of the configuration about a reference point and u the speeds,
 * and _I marks the independent ones:
 *  - chart coordinates: a scalar joint coordinate is its offset from the reference; a unit
 *    quaternion gets Euler-like angles about the reference, R = Rz(heading) Rd(tilt) R_ref
 *    Rn(spin) (heading about the parent z axis, tilt about the horizontal d = e_z x n0, spin
 *    about a body axis n with image n0), named <body>.heading, .tilt, .spin: a turn about the
 *    vertical or a spin about n changes one coordinate alone. A body model has one chart
 *    coordinate per speed; a math-level system's chart is q - q_ref.
 *  - speeds: the model's speeds, except that the speeds of a joint with a heading (planar,
 *    ball, free, plane contact) are taken in its heading frame, turned about the parent z axis
 *    by the chart heading (<body>.heading, or the planar heading's offset). At the reference
 *    they equal the model's speeds; the rotation makes a turn about the vertical a steady
 *    motion and the heading a cyclic coordinate.
 *  - holonomic rows (loop closures, the model's phi) fix the dependent chart coordinates, by
 *    Newton inside every evaluation; the velocity constraints fix the dependent speeds. Both
 *    partitions are chosen once (pivoted QR at the first operating point, preferring the names
 *    in def.independent) and then frozen.
 *
 * Operating points: an equilibrium (independent speeds zero, every independent coordinate
 * free) or a steady motion (the given state, with the variables named in def.free moved):
 * Gauss-Newton drives the speed rows of F and the rows of the freed coordinates to zero.
 * The speed parameter s sets the speeds v_base + s v_dir first (def.speed_dir).
 *
 * Linearization: A = dF/dx column by column, each entry with an error estimate. By default the
 * complex step: F evaluated once on x0 + i h e_j (h = 1e-100) through the model's complex-step
 * build gives column j exactly to round-off, and a second evaluation with another rounding
 * estimates that round-off. Models with C callbacks of doubles (math-level systems, user
 * constraints and user effects, state functions without partial derivatives) fall back to
 * Ridders' extrapolated central differences (ap_lin_method_used and ap_lin_fallback say which
 * and why); def.method chooses either. The input matrix B = dF/dtau for generalized forces tau
 * on the speeds named in def.inputs is exact (F is affine in tau).
 * Cyclic coordinates: the largest set C of coordinate states whose columns of A vanish outside
 * the rows of C; the operating point must be steady in the other rows. Eigenvalues, eigenvectors
 * and their reciprocal condition numbers come from LAPACK's dgeevx.
 *
 * All functions return AP_OK or a negative AP_ERR_* code; ap_lin_message has the details. With
 * L NULL (or an index out of range) the queries give NULL, 0, -1 or, for ap_lin_message, a
 * fixed text, and the others AP_ERR_ARG; ap_lin_create takes def and v NULL as the defaults
 * and zero speeds. */
#ifndef APPELL_ANALYZE_H
#define APPELL_ANALYZE_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/status.h"
#include "appell/system.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ap_lin_about {
  AP_LIN_STEADY = 0,       /* the given state, made steady in the freed variables */
  AP_LIN_EQUILIBRIUM = 1   /* independent speeds zero; every independent coordinate free */
} ap_lin_about;

/* How the Jacobian A = dF/dx is computed. */
typedef enum ap_lin_method {
  AP_LIN_AUTO = 0,         /* complex step where the model has it, else Ridders (default) */
  AP_LIN_COMPLEX_STEP = 1, /* complex step; AP_ERR_UNSUPPORTED (the message names the element)
                              when the model cannot be evaluated that way */
  AP_LIN_RIDDERS = 2       /* Ridders' extrapolated central differences */
} ap_lin_method;

typedef struct ap_lin_def {
  ap_lin_about about;      /* default AP_LIN_STEADY */
  const char *const *free; /* NULL-terminated names of state variables the Newton may move
                              (steady); equilibrium frees every independent coordinate and
                              ignores this. Default NULL: none (the point must be steady) */
  const double *speed_dir; /* (k) model speeds per unit of the speed parameter, or NULL (no
                              speed parameter) */
  const char *const *independent; /* NULL-terminated names preferred as independent
                              coordinates / speeds when the partitions are chosen; default NULL */
  const char *const *inputs; /* NULL-terminated model speed names that receive an input
                              generalized force (a joint torque or force), or MOTOR.setpoint
                              names (a motor's set-point): columns of B */
  double tol;              /* Newton: residual relative to its scale; default 1e-12 */
  int max_iter;            /* Newton iterations; default 40 */
  double zero_tol;         /* an entry of A is a structural zero when |A_ij| is within
                              4 times its error estimate plus zero_tol max|A|; default 1e-9 */
  double h0;               /* Ridders' first step, times max(1, |x_j|); default 0.01 */
  ap_lin_method method;    /* default AP_LIN_AUTO */
  int internal_check;       /* set by ap_lin_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_lin_def;

AP_API ap_lin_def ap_lin_def_default(void);

typedef struct ap_lin ap_lin;

/* Create a linearizer for model m with the guess (t, q, v) (n and k entries; v may be NULL:
 * zero). The definition is copied (names too). AP_ERR_UNSUPPORTED for a math-level system with
 * a kinematic matrix N and n != k, or a joint kind the chart does not know; AP_ERR_ARG for an
 * input that is not a speed, a name in def.free or def.independent that is not a state
 * variable (the message has the closest name), or a NaN or infinity in q, v or def.speed_dir
 * (the message names the entry). On such a failure *out still holds the linearizer, so that
 * ap_lin_message can say why: free it. (NULL arguments: AP_ERR_ARG and *out = NULL.) */
AP_API int ap_lin_create(const ap_model *m, const ap_lin_def *def, double t, const double *q,
                         const double *v, ap_lin **out);
AP_API void ap_lin_free(ap_lin *L);
AP_API const char *ap_lin_message(const ap_lin *L);
/* A function the speed sweep (ap_lin_sweep_speed) calls before each speed it solves (each
 * sweep value, each refinement of a characteristic point), with user: a non-zero return stops
 * the sweep with AP_ERR_INTERRUPTED (ap_lin_message says at which speed). poll NULL: none
 * (default). For Ctrl-C in programs that run long sweeps. */
AP_API void ap_lin_set_poll(ap_lin *L, int (*poll)(void *user), void *user);

/* Find the operating point at speed parameter s (ignored without def.speed_dir; NaN: leave the
 * speeds as they are; an infinity: AP_ERR_ARG). Starts from the last operating point (or the guess), so a sweep is a
 * continuation. The first call chooses the partitions. On success the chart is re-centred on
 * the point. AP_ERR_SINGULAR / AP_ERR_SOLVER when Newton fails (message with the residual). */
AP_API int ap_lin_operating_point(ap_lin *L, double s);
/* The operating point (n coordinates, k model speeds) and t. */
AP_API const double *ap_lin_q(const ap_lin *L);
AP_API const double *ap_lin_v(const ap_lin *L);

/* Linearize about the operating point: A (nx x nx), its error estimates, B (nx x nu), the
 * cyclic states and the steadiness check. AP_ERR_INCONSISTENT when the point is not steady in
 * the non-cyclic rows (message names the row and the rate). */
AP_API int ap_lin_linearize(ap_lin *L);

/* Sizes and names. States are chart coordinates first, then speeds. */
AP_API int ap_lin_nx(const ap_lin *L);
AP_API int ap_lin_nu(const ap_lin *L);
AP_API const char *ap_lin_state_name(const ap_lin *L, int i);
AP_API const char *ap_lin_input_name(const ap_lin *L, int j);
/* 1 for a cyclic coordinate state, 0 otherwise. */
AP_API int ap_lin_is_cyclic(const ap_lin *L, int i);
/* Index of a state by name, -1 if none. */
AP_API int ap_lin_find_state(const ap_lin *L, const char *name);

/* Column-major matrices after ap_lin_linearize: A (nx x nx), Aerr (nx x nx: the error estimate
 * of each entry, complex step's round-off or Ridders'), B (nx x nu), F(x0) (nx: the rates at the
 * point; non-zero only in cyclic rows for a steady motion). */
AP_API const double *ap_lin_A(const ap_lin *L);
AP_API const double *ap_lin_A_error(const ap_lin *L);
AP_API const double *ap_lin_B(const ap_lin *L);
AP_API const double *ap_lin_rates(const ap_lin *L);
/* The method of the last linearization: AP_LIN_COMPLEX_STEP or AP_LIN_RIDDERS (AP_LIN_AUTO
 * before any). */
AP_API ap_lin_method ap_lin_method_used(const ap_lin *L);
/* Why the last linearization under AP_LIN_AUTO used Ridders' method (the element that has no
 * complex-step evaluation: "effect 'drag' is a user effect (a C callback of doubles)"), or ""
 * when it did not fall back. */
AP_API const char *ap_lin_fallback(const ap_lin *L);

/* Eigenvalues of the subsystem on the states sel[0..ns-1] (NULL: every state, or the
 * non-cyclic ones when drop_cyclic). The subsystem must be closed: no state outside it may
 * both depend on it and influence it (AP_ERR_ARG otherwise, naming the coupling). Results go
 * to the ap_lin_eig arrays below (ne entries). */
AP_API int ap_lin_eigen(ap_lin *L, const int *sel, int ns, int drop_cyclic);

typedef struct ap_lin_eig {
  int n;                   /* eigenvalues */
  const int *states;       /* (n) the states of the subsystem */
  const double *re, *im;   /* (n) eigenvalues, conjugate pairs adjacent (positive im first) */
  const double *rcond;     /* (n) reciprocal condition numbers (dgeevx RCONDE) */
  const double *rcondv;    /* (n) of the eigenvectors (RCONDV) */
  const double *err;       /* (n) error bound: (eps ||A|| + ||E||_F) / rcond, E = Ridders'
                              error estimates of the subsystem's entries */
  const double *vr;        /* (n x n) right eigenvectors, dgeev's real storage: for a pair
                              j, j+1 the vector is vr_j +- i vr_{j+1} */
  const double *Asub;      /* (n x n) the subsystem's matrix */
} ap_lin_eig;

AP_API int ap_lin_get_eigen(const ap_lin *L, ap_lin_eig *out);

/* ---- Sweeps ------------------------------------------------------------------------------ */

/* Eigenvalues at parameter p: fill re, im (n entries, n the same at every p). Return codes as
 * the library's. */
typedef int (*ap_lin_eig_fn)(double p, int n, double *re, double *im, void *user);

typedef enum ap_lin_event {
  AP_LIN_CROSSING = 0,     /* the real part of an eigenvalue (or a pair) crosses zero */
  AP_LIN_MEETING = 1       /* two real eigenvalues meet and become a complex pair (or back) */
} ap_lin_event;

typedef struct ap_lin_point {
  ap_lin_event kind;
  double p;                /* the parameter at the event */
  double p_err;            /* its uncertainty: the root finder's final bracket */
  double re, im;           /* the eigenvalue there (the pair's upper member) */
  int index;               /* tracked eigenvalue (column of the sweep's arrays) */
  int rising;              /* crossing: 1 when the real part goes from - to + with p;
                              meeting: 1 when the pair becomes complex as p grows */
} ap_lin_point;

typedef struct ap_lin_sweep {
  int n, count;            /* eigenvalues per point, parameter values */
  double *p;               /* (count) */
  double *re, *im;         /* (n x count, column per parameter value) tracked by continuity:
                              row i follows one eigenvalue across the sweep */
  int npoints;             /* characteristic points found */
  ap_lin_point *points;
} ap_lin_sweep;

/* Eigenvalues at p[0..count-1] (ascending), matched by continuity from one value to the next
 * (assignment by least total distance, with the predicted positions), then every crossing of
 * zero by a real part and every meeting of two real eigenvalues located by a bracketing root
 * finder on a smooth function (the real part; the spread of the cluster of eigenvalues at the
 * meeting point) to |dp| <= ptol. Eigenvalues with |re| <= zero_tol at both ends of an interval
 * count as zero (no crossing). The result owns its arrays: ap_lin_sweep_free. */
AP_API int ap_lin_sweep_run(ap_lin_eig_fn fn, void *user, int n, const double *p, int count,
                            double ptol, double zero_tol, ap_lin_sweep *out, char *msg,
                            size_t msg_len);
AP_API void ap_lin_sweep_free(ap_lin_sweep *s);

/* The speed sweep of a linearizer: at each s the operating point (continuation), the
 * linearization and the eigenvalues of the subsystem chosen by sel / drop_cyclic (as
 * ap_lin_eigen). */
AP_API int ap_lin_sweep_speed(ap_lin *L, const double *s, int count, const int *sel, int ns,
                              int drop_cyclic, double ptol, ap_lin_sweep *out);

#ifdef __cplusplus
}
#endif
#endif
