/* Appell core (internal): the compiled model and the data's private scratch.
 *
 * The model is a validated copy of a math-level system definition (docs/design.md §2, "Math-level
 * systems"); the body layer will compile into the same struct. The data's internal arena holds
 * the factorizations and scratch of the pipeline, sized once in ap_data_create.
 *
 * Generic scalar (linalg/scalar.h). The per-evaluation code of lib/core (data.c, forward.c) and
 * lib/model is written once in ap_sc and compiled twice; the complex-step build works on
 * ap_data_cs, an internal mirror of ap_data whose value arrays are double _Complex (same
 * fields, same meaning; t, the decision outputs (growth, rcond_*, resid_*), the partition and
 * the counters stay double / int). Inside a file compiled with AP_SC_COMPLEX the names ap_data
 * and ap_scratch denote the mirrors (see the end of this header), so the generic source reads
 * as the double one; its public names get _cs (AP_SC). The analysis layer creates a mirror with
 * ap_data_create_cs when it wants exact derivatives. */
#ifndef AP_CORE_H
#define AP_CORE_H

#include <stddef.h>

#include "appell/system.h"
#include "core/arena.h"
#include "linalg/scalar.h"

typedef struct ap_data_cs ap_data_cs;
typedef struct ap_ops ap_ops;   /* core/structured.h */
typedef struct ap_st ap_st;

/* A model compiled from bodies (lib/model) evaluates its own g, N, A, a0 and h, Q, gamma in
 * place of user callbacks. Its per-data scratch (ev.scratch doubles) lives in the data, so one
 * model can serve many data at once. Every hook returns AP_OK, AP_RECOVERABLE or AP_ERR_*
 * and writes d->msg on failure. */
typedef struct ap_evaluator {
  size_t scratch;           /* doubles of scratch per data */
  /* position stage: g (k x k), N (n x k), A (b x k), a0 (b) at (d->t, d->q); the arrays are
   * zeroed before the call */
  int (*position)(const ap_model *m, ap_data *d, double *scratch);
  /* velocity stage: h (k), Q (k), gamma (b) at (d->t, d->q, d->v), after position; zeroed
   * before the call */
  int (*velocity)(const ap_model *m, ap_data *d, double *scratch);
  /* after an accepted step: put q back on its manifold (unit quaternions, loop closures);
   * *change = size of the correction. May be NULL. */
  int (*project_q)(const ap_model *m, ap_data *d, double *q, double *scratch, double *change);
  /* Implicit holonomic constraints phi(q, t) = 0 (m->nphi rows: loop closures, unit-quaternion
   * norms) for the DAE mode's stabilized index-2 (GGL) form: phi (nphi) and its Jacobian with
   * respect to q, Phi_q (nphi x n, column-major, ld nphi; zeroed by the caller), at
   * (d->t, d->q) after the position stage there (it reads that stage's kinematics); Phi_q
   * may be NULL (phi only). The hook is NULL when nphi == 0. */
  int (*phi)(const ap_model *m, ap_data *d, double *scratch, double *phi, double *Phi_q);
  /* After an accepted step of a mode that must not move q (DAE): the checks of project_q
   * without the corrections (a disk or torus reaching lying flat). May be NULL. */
  int (*check_q)(const ap_model *m, ap_data *d, const double *q, double *scratch);
  void (*destroy)(void *impl);   /* frees impl with the model */
  void *impl;
  /* The complex-step build of position, velocity and phi (same contracts on ap_data_cs and
   * double _Complex scratch of the same length). NULL when the model has none: math-level
   * systems (their callbacks are C functions of doubles). */
  int (*position_cs)(const ap_model *m, ap_data_cs *d, double _Complex *scratch);
  int (*velocity_cs)(const ap_model *m, ap_data_cs *d, double _Complex *scratch);
  int (*phi_cs)(const ap_model *m, ap_data_cs *d, double _Complex *scratch,
                double _Complex *phi, double _Complex *Phi_q);
  /* Whether the complex-step build can evaluate this model: 0, or -1 with a message of at most
   * len bytes naming the element that offers only a C callback of doubles (a user constraint
   * or user effect). May be NULL when position_cs is NULL. */
  int (*cs_blocker)(const ap_model *m, char *msg, size_t len);
  /* The sections of the scratch (a body model's bodies, joints, ... ; core/arena.h), or NULL.
   * In the guard build the dense path's data fills and checks their guards with its own. */
  const ap_arena *layout;
  /* Optional (compiled models, lib/codegen): the dense path's acceleration stage of the double
   * build, the same operations as fwd_acceleration's at the model's sizes; AP_ERR_UNSUPPORTED
   * when it does not take this evaluation (then the core's own runs and reports). */
  int (*acceleration)(const ap_model *m, ap_data *d);
  /* Optional (compiled models), double build: 1 when every output of a stage (0, position: g,
   * A, a0; 1, velocity: h, Q, gamma) is finite and at most AP_HUGE in magnitude (one pass);
   * 0: the core runs its per-array checks, which name the array and entry (the hook may have
   * evaluated the stage again, as the interpreted path does, so they name the same entry). */
  int (*finite)(const ap_model *m, ap_data *d, int stage);
  /* Optional (compiled models), double build: ap_la_partition_basis without a condition
   * estimate (F, tau, B, b0, growth, *resid) and ap_la_partition_particular (w, resid_gamma)
   * at the model's sizes, with the same results; AP_ERR_UNSUPPORTED when not taken (then the
   * linalg routine runs and reports). */
  int (*basis)(const ap_model *m, ap_data *d, double *resid);
  int (*particular)(const ap_model *m, ap_data *d);
} ap_evaluator;

struct ap_model {
  ap_system_def sys;        /* callbacks and sizes; names point into the arrays below */
  ap_evaluator ev;          /* set by the body layer; all NULL for math-level systems */
  int n, k, b;
  int nphi;                 /* rows of ev.phi; 0 for math-level systems */
  int nhol;                 /* implicit holonomic rows among the constraint rows (loop
                               closures, wheel contacts): redundancy among the rows may then
                               hold only where they are closed; 0 for math-level systems */
  double lscale;            /* length scale (m): the largest frame offset, contact point or
                               shape size of a body model; 1 for math-level systems. The scale
                               of the gradients of the holonomic rows phi (a contact height or
                               loop gap moves with the angles by lever arms of this size):
                               a row of Phi_q below rank_rtol lscale vanishes identically */
  double *vscale;           /* (k) the scale of each speed's unit of motion: lscale for a linear
                               speed (m/s), 1 for an angular one (rad/s); NULL (math-level
                               systems): 1 for every speed. ap_partition's nearby state moves
                               q by 1e-6 N (vscale . xi), xi a spread of unit entries */
  char name[64];
  char **coord_names;       /* (n) */
  char **speed_names;       /* (k) */
  char **constraint_names;  /* (b) */
  /* The tree path (docs/large.md): the structured operators chosen at compile time, or NULL
   * (the dense path). A data made for such a model has no g, N, A, B, G (NULL) and runs the
   * stages of core/structured.c; the complex-step build always takes the dense path. */
  const ap_ops *ops;
  void *ops_impl;           /* owner of ops, freed by ops_destroy with the model */
  void (*ops_destroy)(void *impl);
};

/* Scratch owned by one ap_data (no allocation after ap_data_create). */
typedef struct ap_scratch {
  double *F;                /* QR factor: (b x k) partitioned, (k x b) orthonormal */
  double *tau;              /* Householder scalars (max(b, k)) */
  int *jpvt;                /* row order of A (b), orthonormal basis */
  double *Qf;               /* full orthogonal factor of A^T (k x k) */
  double *dg;               /* metric derivative (n x k x k), Christoffel bias only */
  double *gB;               /* g B (k x l) */
  double *tk1, *tk2;        /* k-vectors */
  double *tl;               /* l-vector */
  double *tn;               /* n-vector (ap_partition: q while it tries a nearby state) */
  double *work;             /* linalg scratch, ap_la_work_size(b, k) doubles */
  double *ev;               /* evaluator scratch, m->ev.scratch doubles (may be NULL) */
  int *iwork;               /* linalg scratch, ap_la_iwork_size(b, k) ints */
  const ap_model *model;    /* the model the data was made for (buffers sized for it) */
  int judge_at_accepted;    /* 1: the caller judges every redundant row's consistency at its
                               accepted states (ap_core_judge_redundant after the stages):
                               a multistep stepper's trial states (predictor, Newton
                               iterates, difference-quotient columns) lie off A v + a0 = 0 */
  ap_st *st;                /* the tree path's structured state (m->ops), else NULL */
  const double *input_Q;    /* (k) generalized forces added to Q by the velocity stage: a
                               simulation's inputs (lib/integrate/sim_input.c), or NULL */
  const double *setpoint_in; /* (effects) motor set-points that are inputs, used in place of
                               the motor's value; NaN where the motor keeps its own; or NULL */
} ap_scratch;

/* Q += the data's input forces, when it has them (the velocity stage, double build only: the
 * linearizer takes the inputs' columns of B apart, exactly). */
static inline void ap_core_add_inputs(const ap_model *m, ap_data *d) {
  const double *u = ((const ap_scratch *)d->internal)->input_Q;
  for (int i = 0; u && i < m->k; i++) d->Q[i] += u[i];
}

/* The structured state of a data on the tree path, or NULL (double build only). */
static inline ap_st *ap_core_st(const ap_data *d) {
  return ((const ap_scratch *)d->internal)->st;
}

/* 1 when m and d are not NULL and d was made by ap_data_create for m: the public functions
 * that take (m, d) return AP_ERR_ARG otherwise. */
static inline int ap_core_data_ok(const ap_model *m, const ap_data *d) {
  return m && d && d->internal && ((const ap_scratch *)d->internal)->model == m;
}

/* Relative size beyond which a redundant constraint row is called inconsistent when the
 * redundancy holds for every q (structural: the residual is round-off) and the rows are judged
 * at every evaluation. Redundancy that holds only on the manifold of the implicit holonomic
 * rows (loops, wheel contacts) is judged against d->manifold_rtol at accepted states instead:
 * a stepper's trial states lie off that manifold by O(h^2), and there the dropped rows are
 * neither dependent nor consistent (least squares over all rows keeps the solve smooth). */
#define AP_CONSISTENCY_RTOL 1e-8

/* The scale the consistency residuals of redundant rows are judged against: the size of the
 * terms of the constraint equations, row by row, t_r = |a0_r| + sum_c |A_rc v_c| for the free
 * terms a0 (A v + a0 = 0: the units of row r, m/s or rad/s), t_r = |gamma_r| + sum_c |A_rc v'_c|
 * for gamma (A v' = gamma; v' of the last acceleration stage), each plus a floor f_r =
 * AP_ROW_FLOOR_PER_S sum_c |A_rc| vscale_c (resp. AP_ROW_FLOOR_PER_S2, per s^2): the row's terms
 * at a speed of one model length scale (or one radian) per second. The floor keeps the
 * round-off of a0 and gamma, which comes from terms the core does not see (4e-16 in
 * car_ackermann.yaml at rest, where t_r is that round-off itself; 1.5e-15 against terms of 6e-6
 * in a campaign model), from counting; it is the one part with a unit of time (s). Each term
 * pairs an entry of A with the speed it multiplies, so t_r and f_r scale with the model's units
 * of length and mass as row r does: a model in millimetres or kilometres, or in grams, is judged
 * as the one in metres and kilograms; in milliseconds the floor is 1000 times larger. ap_partition (and ap_core_judge_redundant)
 * judge each dropped row j, the combination c of the kept rows it equals, against its own
 * terms: |x_j - c . x_kept| > tol (t_j + sum_i |c_i| t_i) is inconsistent. The stages' checks at
 * every evaluation judge the residual of all rows at once against the largest row's terms,
 * ap_core_row_scale (max_r t_r, plus AP_TERMS_TINY): rows of different units (a knife edge in
 * m/s beside a prescribed rate in rad/s) are then judged against the larger ones.
 * AP_TERMS_TINY is the reciprocal of AP_HUGE: with A = 0, v = 0 and a0 = 0 the residual is the
 * round-off of zero (8e-221 was seen) and must not count. */
#define AP_TERMS_TINY 1e-150
#define AP_ROW_FLOOR_PER_S 1.0
#define AP_ROW_FLOOR_PER_S2 1.0
double ap_core_row_scale(const ap_model *m, const ap_data *d, int of_gamma);
double ap_core_row_scale_cs(const ap_model *m, const ap_data_cs *d, int of_gamma);

/* The position stage's objects g, N, A, a0 without the basis and without counting a stage
 * (forward.c; ap_partition evaluates nearby states with it). */
int ap_core_position_objects(const ap_model *m, ap_data *d);

/* Largest magnitude a model quantity may have: the steppers' error norms square the state's
 * derivatives, and past 1e154 the square overflows (the step size, then the time, become NaN). */
#define AP_HUGE 1e150

/* Check that x[0..len-1] is finite and at most AP_HUGE in magnitude; otherwise write a message
 * naming the callback, the entry and the value. */
int ap_core_check_finite(const ap_model *m, ap_data *d, const char *what, const double *x,
                         int rows, int cols);

/* Translate a callback's return code into a status with a message. */
int ap_core_callback_status(const ap_model *m, ap_data *d, const char *what, int rc);

/* ap_project_speeds without the position stage: the data's g, B, b0 must be current. */
int ap_core_project_here(const ap_model *m, ap_data *d, double *v, double *change);

/* The consistency of redundant rows that hold only on the holonomic manifold, judged at an
 * accepted state (after ap_fwd_position and ap_fwd_velocity there, q projected): the residuals
 * of a0 and gamma on the dropped rows against d->manifold_rtol. AP_ERR_INCONSISTENT with the
 * rows named; AP_OK when the model has no such rows. */
int ap_core_judge_redundant(const ap_model *m, ap_data *d);

/* A constraint row that no speed moves (|A_r| below rank_rtol times m->lscale) while its a0 is
 * not round-off: AP_ERR_INCONSISTENT with the row and the numbers in d->msg; AP_OK otherwise.
 * A and a0 must be current (after ap_partition; on the tree path the rows' norms come from its
 * operator A x + a0, one product per speed); partition.c. */
int ap_core_refuse_vanishing_rows(const ap_model *m, ap_data *d);

/* x <- B G^-1 B^T g x: the g-orthogonal projection onto the null space of A, with the factor
 * of G left by ap_core_project_here. */
void ap_core_project_tangent(const ap_model *m, ap_data *d, double *x);

/* v = B e' + b0 from the data's position stage (partitioned basis). */
void ap_core_speeds(const ap_model *m, ap_data *d);

/* Guard build (meson -Dguards=true, core/arena.h): check the guard words of d's blocks after
 * the stage named; AP_ERR_INTERNAL with a message naming the array overrun and the stage when
 * one is hit, else rc. Without guards AP_CORE_GUARDED is rc itself: no code, no cost. */
int ap_core_guards(const ap_model *m, ap_data *d, const char *stage, int rc);
#if AP_GUARDS
#define AP_CORE_GUARDED(m, d, stage, rc) AP_SC(ap_core_guards)(m, d, stage, rc)
#else
#define AP_CORE_GUARDED(m, d, stage, rc) (rc)
#endif

/* printf into d->msg. */
void ap_core_msg(ap_data *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ---- the complex-step mirror ------------------------------------------------------------- */

/* ap_data with double _Complex value arrays (field by field as in appell/system.h). */
struct ap_data_cs {
  int n, k, b;
  double t;
  double _Complex *q, *v, *e;
  ap_basis basis;
  int speeds_from_e, want_reactions, estimate_cond;   /* estimate_cond must stay 0 */
  double rank_rtol, manifold_rtol;
  int *perm;
  int rank, l, redundant, redundant_manifold;
  double _Complex *g, *N, *A, *a0, *B, *b0;
  double growth, rcond_R, resid_a0;
  double _Complex *h, *Q, *gamma, *w;
  double resid_gamma;
  double _Complex *G, *Phi;
  double rcond_G;
  double _Complex *edd, *vdot, *qdot, *lambda;
  ap_counters cnt;
  char msg[512];
  void *internal;
};

/* Every field of ap_data has its mirror at the same offset (the lists below name every field of
 * both; a field added to one and not the other changes the size of one of them). */
_Static_assert(sizeof(struct ap_data_cs) == sizeof(ap_data), "ap_data_cs mirrors ap_data");
#define AP_DATA_FIELDS(X)                                                                  \
  X(n) X(k) X(b) X(t) X(q) X(v) X(e) X(basis) X(speeds_from_e) X(want_reactions)           \
  X(estimate_cond) X(rank_rtol) X(manifold_rtol) X(perm) X(rank) X(l) X(redundant)         \
  X(redundant_manifold) X(g) X(N) X(A) X(a0) X(B) X(b0) X(growth) X(rcond_R) X(resid_a0)   \
  X(h) X(Q) X(gamma) X(w) X(resid_gamma) X(G) X(Phi) X(rcond_G) X(edd) X(vdot) X(qdot)     \
  X(lambda) X(cnt) X(msg) X(internal)
#define AP_DATA_MIRROR(f)                                                                  \
  _Static_assert(offsetof(struct ap_data_cs, f) == offsetof(ap_data, f),                   \
                 "ap_data_cs." #f " is at the offset of ap_data." #f);
AP_DATA_FIELDS(AP_DATA_MIRROR)
#undef AP_DATA_MIRROR

typedef struct ap_scratch_cs {
  double _Complex *F, *tau;
  int *jpvt;
  double _Complex *Qf, *dg, *gB, *tk1, *tk2, *tl, *tn, *work, *ev;
  int *iwork;
  const ap_model *model;
  int judge_at_accepted;
} ap_scratch_cs;
/* The scratch mirrors ap_scratch field by field (ap_scratch's st has no mirror: the complex
 * build always takes the dense path). */
#define AP_SCRATCH_FIELDS(X)                                                               \
  X(F) X(tau) X(jpvt) X(Qf) X(dg) X(gB) X(tk1) X(tk2) X(tl) X(tn) X(work) X(ev) X(iwork)   \
  X(model) X(judge_at_accepted)
#define AP_SCRATCH_MIRROR(f)                                                               \
  _Static_assert(offsetof(ap_scratch_cs, f) == offsetof(ap_scratch, f),                    \
                 "ap_scratch_cs." #f " is at the offset of ap_scratch." #f);
AP_SCRATCH_FIELDS(AP_SCRATCH_MIRROR)
#undef AP_SCRATCH_MIRROR

static inline int ap_core_data_ok_cs(const ap_model *m, const ap_data_cs *d) {
  return m && d && d->internal && ((const ap_scratch_cs *)d->internal)->model == m;
}

/* The complex-step build's entry points (forward.c, data.c compiled with AP_SC_COMPLEX). The
 * partition (perm, rank, l, redundant, redundant_manifold) is not chosen here: copy it from a
 * double data at the real part (ap_core_copy_partition). The basis is AP_BASIS_PARTITIONED or
 * AP_BASIS_NONE; reactions and condition estimates are not available. AP_ERR_UNSUPPORTED for a
 * model without the complex build (ev.position_cs NULL) and for the orthonormal basis. */
int ap_data_create_cs(const ap_model *m, ap_data_cs **out);
void ap_data_free_cs(ap_data_cs *d);
int ap_core_position_objects_cs(const ap_model *m, ap_data_cs *d);
int ap_fwd_position_cs(const ap_model *m, ap_data_cs *d);
int ap_fwd_velocity_cs(const ap_model *m, ap_data_cs *d);
int ap_fwd_acceleration_cs(const ap_model *m, ap_data_cs *d);
int ap_forward_cs(const ap_model *m, ap_data_cs *d);
void ap_core_speeds_cs(const ap_model *m, ap_data_cs *d);
int ap_core_guards_cs(const ap_model *m, ap_data_cs *d, const char *stage, int rc);
int ap_core_check_finite_cs(const ap_model *m, ap_data_cs *d, const char *what,
                            const double _Complex *x, int rows, int cols);
void ap_core_msg_cs(ap_data_cs *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* The partition and tolerances of src (a double data of the same model) into dst. */
void ap_core_copy_partition(const ap_data *src, ap_data_cs *dst);
/* 1 when the model can be evaluated by the complex-step build; otherwise 0 and a message of at
 * most len bytes that names why (a math-level system, a user callback). */
int ap_core_has_cs(const ap_model *m, char *msg, size_t len);

/* Inside the complex-step build of a generic file of lib/core and lib/model, ap_data and
 * ap_scratch name the mirrors. (lib/analyze holds both kinds in one struct: its generic files
 * define AP_SC_EXPLICIT_DATA and spell AP_SC(ap_data).) */
#if defined(AP_SC_COMPLEX) && !defined(AP_SC_EXPLICIT_DATA)
#define ap_data ap_data_cs
#define ap_scratch ap_scratch_cs
#define ap_core_data_ok ap_core_data_ok_cs
#endif

#endif
