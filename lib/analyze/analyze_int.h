/* Appell analysis layer (internal): the linearizer's struct and the functions its files share
 * (prefix ap_an_).
 *
 * Layout of the layer (docs/linearize.md is the user's reference):
 *   chart.c      the chart of the configuration about a reference point and the heading frames
 *   chart_map.c  the chart's maps (q from delta, its Jacobian, rates, heading frames)
 *   reduced.c    F(x): holonomic rows solved, speeds completed, the Appell solve, rates
 *   ridders.c    Ridders' extrapolated central differences for a column of a Jacobian
 *   point.c      the partitions and the operating point (Gauss-Newton)
 *   linearize.c  the public object: create, linearize, cyclic states, queries
 *   eigen.c      dgeevx, condition numbers, closed subsystems
 *   sweep.c      sweeps: tracking by continuity, characteristic points by root finding
 *
 * Variables: the nc chart coordinates (index c), then the k speeds (index nc + s). The state x
 * holds the independent ones: x[i] is variable xvar[i]. Invariant: after a successful
 * ap_lin_operating_point the chart is centred on the point (q_ref, v_ref), so the state there is
 * x0 = (0, v_ref[independent speeds]).
 *
 * Generic scalar (linalg/scalar.h): chart_map.c and reduced.c are compiled twice; the
 * complex-step build (*_cs.c) evaluates F on x0 + i h e_j for exact Jacobian columns, with its
 * own data (ap_data_cs) and scratch (an_ws_cs). The declarations below marked "generic" name
 * the *_cs functions in that build. */
#ifndef AP_ANALYZE_INT_H
#define AP_ANALYZE_INT_H

#include <float.h>
#include <stddef.h>

#define AP_SC_EXPLICIT_DATA 1   /* this layer spells AP_SC(ap_data) (core/core.h) */
#include "appell/analyze.h"
#include "core/core.h"

#ifdef AP_SC_COMPLEX   /* the complex-step build's names of the generic functions */
#define ap_an_chart_apply ap_an_chart_apply_cs
#define ap_an_chart_jacobian ap_an_chart_jacobian_cs
#define ap_an_chart_rates ap_an_chart_rates_cs
#define ap_an_frame_to_u ap_an_frame_to_u_cs
#define ap_an_frame_to_v ap_an_frame_to_v_cs
#define ap_an_frame_rates ap_an_frame_rates_cs
#define ap_an_frame_matrix ap_an_frame_matrix_cs
#define ap_an_state ap_an_state_cs
#define ap_an_rates ap_an_rates_cs
#define ap_an_rates_full ap_an_rates_full_cs
#endif

/* ---- the chart (chart.c) ---------------------------------------------------------------- */

typedef struct an_quat {
  int q;                    /* index in q of the quaternion's w */
  int c[3];                 /* chart indices of heading, tilt, spin (those of wz, wx, wy) */
  double nb[3];             /* spin axis in body axes */
  double n0[3], d[3];       /* spin axis and tilt axis (unit, horizontal) in parent axes at
                               the reference */
} an_quat;

typedef struct an_frame {
  int h;                    /* chart index of the heading (a quaternion's or a planar one) */
  int npair;
  int pair[2][2];           /* speed index pairs (along x, along y) turned by the heading */
} an_frame;

typedef struct an_chart {
  int nc;                   /* chart coordinates */
  int k;                    /* speeds */
  int body;                 /* body model: chart index c is speed c; math-level: q - q_ref */
  int *qof;                 /* (nc) index in q of a scalar chart coordinate, -1 in a quaternion */
  int nquat, nframe;
  an_quat *quat;
  an_frame *frame;
  char **names;             /* (nc) */
} an_chart;

int ap_an_chart_build(const ap_model *m, an_chart *ch, char *msg, size_t len);
/* Centre the quaternion charts on q_ref: spin axis (the child frame's z axis unless it is
 * within 26 degrees of the vertical; else its most horizontal axis), its image n0 and the tilt axis
 * d = unit(e_z x n0). keep_axis: keep the spin axis chosen before while it stays regular. */
void ap_an_chart_centre(an_chart *ch, const double *q_ref, int keep_axis);
void ap_an_chart_free(an_chart *ch);
/* The maps (chart_map.c, generic). q = chart(q_ref, delta). */
void ap_an_chart_apply(const an_chart *ch, int n, const double *q_ref, const ap_sc *delta,
                       ap_sc *q);
/* dq/ddelta (n x nc, ld n) at delta (body models; math-level: identity). */
void ap_an_chart_jacobian(const an_chart *ch, int n, const ap_sc *q, const ap_sc *delta,
                          ap_sc *J);
/* Chart rates from the model speeds v (body models): scalar c' = v_c, rotation vector
 * rates from the angular speeds. */
void ap_an_chart_rates(const an_chart *ch, const ap_sc *delta, const ap_sc *v, ap_sc *dd);
/* Heading-frame speeds u = S(delta) v, and back v = S^T u (in place allowed). */
void ap_an_frame_to_u(const an_chart *ch, const ap_sc *delta, const ap_sc *v, ap_sc *u);
void ap_an_frame_to_v(const an_chart *ch, const ap_sc *delta, const ap_sc *u, ap_sc *v);
/* Rates of the heading-frame speeds: u' = S v' + S' v, with the chart rates dd. */
void ap_an_frame_rates(const an_chart *ch, const ap_sc *delta, const ap_sc *dd,
                       const ap_sc *v, const ap_sc *vdot, ap_sc *udot);
/* The constraint matrix on the heading-frame speeds: Au = A S^T (b x k, ld b). */
void ap_an_frame_matrix(const an_chart *ch, const ap_sc *delta, int b, const ap_sc *A,
                        ap_sc *Au);

/* ---- the scratch of one evaluation of F (reduced.c), in each build's scalar ---------------- */

/* The double one points into the linearizer's own arrays (point.c uses them too); the complex
 * one is allocated when exact derivatives are first asked for. Sizes as alloc_all's. */
typedef struct an_ws {
  ap_data *d;
  double *delta, *dq, *Jh, *phi, *Phi_q, *Au, *Bu, *b0u, *F, *tau, *u, *dd, *work, *full;
} an_ws;

typedef struct an_ws_cs {
  ap_data_cs *d;
  double _Complex *delta, *dq, *Jh, *phi, *Phi_q, *Au, *Bu, *b0u, *F, *tau, *u, *dd, *work;
  double _Complex *full;
} an_ws_cs;

/* ---- the linearizer ---------------------------------------------------------------------- */

struct ap_lin {
  const ap_model *m;
  ap_data *d;
  ap_lin_def def;           /* copy; its name lists point into names below */
  char **names;             /* owned copies of every name list (one allocation each) */
  double *speed_dir;        /* (k) or NULL */
  int n, k, b, nphi;
  an_chart ch;
  double t;
  double *q_ref, *v_ref;    /* the reference point: the guess, then the operating point */
  double *q_guess, *v_guess;/* the guess as given (speed parameter: v_base = v_guess) */

  /* partitions (point.c), frozen after the first operating point */
  int parted;
  int rh, nci;              /* rank of the holonomic rows; independent chart coordinates */
  int *cperm;               /* (nc) dependent chart coordinates first, then independent */
  int ru, l;                /* rank of A; independent speeds */
  int *uperm;               /* (k) dependent speeds first, then independent */
  int nx, nu;
  int *xvar;                /* (nx) variable of each state */
  int *inputs;              /* (nu) model speed of each input */
  double *x0;               /* (nx) the state at the operating point */

  /* results (linearize.c) */
  int linearized;
  double *A, *Aerr, *Bm, *F0, *noise;
  int *cyclic;              /* (nx) */

  /* eigenvalues (eigen.c) */
  int ne;
  int *esel;
  double *ere, *eim, *ercond, *ercondv, *eerr, *evr, *Asub;

  /* scratch (reduced.c, point.c) */
  double *delta, *dq, *Jh, *phi, *Au, *Bu, *b0u, *F, *tau, *u, *udot, *dd, *work, *f1, *f2;
  double *ridders;          /* Ridders' tableau */
  int *iwork;
  size_t nwork;
  an_ws ws;                 /* views of the arrays above for reduced.c */
  an_ws_cs ws_cs;           /* the complex-step build's (ws_cs.d NULL until first needed) */
  double _Complex *xc, *fc; /* (nx) complex-step state and rates */
  ap_lin_method used;       /* the method of the last linearization */
  char fallback[512];       /* why Ridders' method was used under AP_LIN_AUTO ("" otherwise) */
  char msg[512];
  const char *bad_list;     /* "free", "independent" or "inputs" when a name there is not a
                               variable (a speed, for inputs) */
  int bad_index;            /* its entry */
  int (*poll)(void *user);  /* ap_lin_set_poll: asked before each speed of a sweep */
  void *poll_user;
};

void ap_an_msg(ap_lin *L, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Name of variable i (chart coordinate or model speed). */
const char *ap_an_var_name(const ap_lin *L, int i);
/* Variable index of a name (chart coordinates and speeds), -1 if none. */
int ap_an_find_var(const ap_lin *L, const char *name);

/* ---- the reduced equations (reduced.c) ---------------------------------------------------- */

/* Put the state x into (delta, q, v): dependent chart coordinates by Newton on the holonomic
 * rows, dependent speeds from the velocity constraints, in the heading frames; runs the
 * position stage. On return L->d holds q and v. */
int ap_an_state(ap_lin *L, const ap_sc *x);   /* generic */
/* F(x) (nx): rates of the states. Leaves L->d after a full forward solve at x (generic). */
int ap_an_rates(ap_lin *L, const ap_sc *x, ap_sc *f);
/* Rates of every variable (nc chart rates, then k speed rates) at x, into full (nc + k)
 * (generic). */
int ap_an_rates_full(ap_lin *L, const ap_sc *x, ap_sc *full);
/* F on complex-step states (reduced_cs.c), for jacobian.c. */
int ap_an_rates_cs(ap_lin *L, const double _Complex *x, double _Complex *f);

/* ---- the Jacobian (jacobian.c) ------------------------------------------------------------ */

/* L->A and L->Aerr at L->x0 by the method of def.method (complex step or Ridders; L->used,
 * L->fallback). Leaves the data anywhere: evaluate at x0 after it. */
int ap_an_jacobian(ap_lin *L);
/* Frees the complex-step workspace (ap_lin_free). */
void ap_an_ws_cs_free(ap_lin *L);

/* ---- Ridders (ridders.c) ------------------------------------------------------------------ */

/* A vector function of a vector: f (m) at x. */
typedef int (*ap_an_fn)(const double *x, double *f, void *user);

/* Column j of the Jacobian of fn at x (n entries, x is restored) by Ridders' method: central
 * differences at steps h, h/1.4, h/1.4^2, ... extrapolated by Neville's scheme, each of the m
 * components keeping the extrapolation with the least error estimate and stopping when the
 * error grows past twice its best. The estimate err is at least the round-off of the chosen
 * entry for function values of relative accuracy epsf (AP_AN_EPSF: a few ulps) or absolute
 * noise noise[c] (may be NULL; see ap_an_noise). df, err: m entries; scratch:
 * ap_an_ridders_scratch(m) doubles. Returns the first failure of fn. */
#define AP_AN_EPSF (8.0 * DBL_EPSILON)
size_t ap_an_ridders_scratch(int m);
int ap_an_ridders(ap_an_fn fn, void *user, int n, double *x, int j, double h, double epsf,
                  const double *noise, int m, double *df, double *err, double *scratch);
/* The noise (standard deviation) of each of the m components of fn near x, measured from the
 * sixth differences of fn at x + i d p, i = 0..AP_AN_NOISE_PTS-1, along a fixed direction p
 * with |p_j| = max(1, |x_j|) and d = 1e-5 (a smooth component's sixth difference there is
 * ~1e-30 of its sixth derivative; what remains is round-off). noise: m entries; scratch:
 * (AP_AN_NOISE_PTS + 1) m + n doubles. */
#define AP_AN_NOISE_PTS 14
int ap_an_noise(ap_an_fn fn, void *user, int n, const double *x, int m, double *noise,
                double *scratch);

/* ---- operating points (point.c) ----------------------------------------------------------- */

int ap_an_partition(ap_lin *L);
int ap_an_newton(ap_lin *L);
/* Re-centre the chart on the state x: q_ref, v_ref from ap_an_state(x), x0 = (0, u_I). */
int ap_an_recentre(ap_lin *L, const double *x);

/* ---- eigenvalues (eigen.c) ---------------------------------------------------------------- */

int ap_an_eigen_alloc(ap_lin *L);
void ap_an_eigen_free(ap_lin *L);

#endif
