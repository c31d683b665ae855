/* Appell codegen layer (internal): C generated for one body model, compiled at load time.
 *
 * The generator runs the kinematics of lib/model/kinematics.c once on traced values (cg_v):
 * constants (model parameters, structural zeros) fold at generation time, everything that
 * depends on (q, v) is written out as one C statement per operation, in the same order and
 * with the same association as the interpreted code, so the generated code computes the same
 * floating-point numbers (a multiplication by a constant 1 or 0 and an addition of a constant
 * 0 are dropped: exact except for the sign of a zero). It is a partial evaluation of the
 * interpreted method, not a symbolic re-derivation.
 * docs/compiled.md has the user's side; docs/design.md the layer. */
#ifndef AP_CODEGEN_CODEGEN_H
#define AP_CODEGEN_CODEGEN_H

#include <stddef.h>

#include "appell/compiled.h"
#include "model/model.h"

/* ---- traced scalars and the text they emit (trace.c) ------------------------------------- */

enum { CG_CONST, CG_TEMP, CG_REF };

typedef struct cg_v {
  int kind;
  double c;       /* CG_CONST */
  int id;         /* CG_TEMP: the temporary t<id> */
  char base;      /* CG_REF: the array base[idx] (q, v, S, z) */
  size_t idx;
} cg_v;

typedef struct cg_gen {
  char *s;
  size_t len, cap;
  int fail;       /* out of memory */
  int ntemp;
} cg_gen;

void cg_printf(cg_gen *G, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The source is compiled as up to CG_MAX_TU translation units side by side (cache.c): every
 * top-level function (with the static helpers only it calls) starts with cg_tu, which writes
 * CG_TU_MARK; the text before the first mark (includes, typedefs, declarations) opens every
 * unit. A piece may use only that prelude and what it defines itself. */
#define CG_TU_MARK "/* appell: unit */\n"
#define CG_MAX_TU 2
void cg_tu(cg_gen *G);
cg_v cg_const(double c);
cg_v cg_ref(char base, size_t idx);
void cg_text(const cg_v *a, char *out, size_t len);
cg_v cg_add(cg_gen *G, cg_v a, cg_v b);
cg_v cg_sub(cg_gen *G, cg_v a, cg_v b);
cg_v cg_mul(cg_gen *G, cg_v a, cg_v b);
cg_v cg_neg(cg_gen *G, cg_v a);
cg_v cg_div(cg_gen *G, cg_v a, cg_v b);
cg_v cg_call(cg_gen *G, const char *fn, cg_v a);      /* sin, cos */
cg_v cg_quat_scale(cg_gen *G, cg_v nn);                /* nn > 0 ? 2 / nn : 0 */

/* The inline helpers of model/model.h and rot.c on traced values (same order of operations). */
cg_v t_dot(cg_gen *G, const cg_v *a, const cg_v *b);
void t_cross(cg_gen *G, const cg_v *a, const cg_v *b, cg_v *c);
void t_axpy(cg_gen *G, cg_v s, const cg_v *a, cg_v *c);
void t_cross_add(cg_gen *G, const cg_v *a, const cg_v *b, cg_v *c);
void t_m3v(cg_gen *G, const cg_v *M, const cg_v *x, cg_v *y);
void t_m3tv(cg_gen *G, const cg_v *M, const cg_v *x, cg_v *y);
void t_m3m(cg_gen *G, const cg_v *A, const cg_v *B, cg_v *C);
void t_m3mt(cg_gen *G, const cg_v *A, const cg_v *B, cg_v *C);
void t_axis_angle(cg_gen *G, const double *axis, cg_v angle, cg_v *R);
void t_quat_matrix(cg_gen *G, const cg_v *q, cg_v *R);
void t_consts(const double *x, int n, cg_v *out);

/* ---- the kinematics on traced values (emit_kin.c, emit_vel.c) ---------------------------- */

/* The traced scratch: one value per scratch double, and whether the stage being traced wrote
 * it (offsets from a real scratch-sized array, so the views of model.h give them). */
typedef struct cg_kin {
  const ap_bmodel *M;
  cg_gen *G;
  double *base;          /* M->scratch doubles, only for the offsets of the views */
  cg_v *sh;              /* traced scratch */
  unsigned char *wr;     /* written in this stage */
  cg_v *out;             /* g (k x k) or h (k) */
  unsigned char *owr;
  size_t text0;          /* where the stage's text starts in G->s */
  int id0;               /* its first temporary */
} cg_kin;

static inline cg_v *cg_at(cg_kin *K, const double *p) { return K->sh + (p - K->base); }
void cg_mark(cg_kin *K, const double *p, int n);
/* Emit the position stage's body (joints, bodies, g) and the velocity stage's (velocities,
 * biases, h); then their stores. 0, or -1 when the model has what the generator does not take
 * (why: a reason of at most len bytes). */
int cg_kin_supported(const ap_bmodel *M, char *why, size_t len);
void cg_kin_position(cg_kin *K);
void cg_kin_velocity(cg_kin *K);
void cg_kin_store(cg_kin *K, const char *out_name, int nout);

/* The acceleration stage at the model's sizes (emit_acc.c), g's structure from the position
 * stage's traced g (gpos, k x k). indep (l = k - b entries, or NULL): the variant for a
 * partition whose independent speeds are indep, B's rows there the identity and w 0 there
 * (folded; the variant checks those entries first, and on a mismatch returns what
 * apc_acceleration returns). */
int cg_kin_acceleration(cg_gen *G, const ap_bmodel *M, const cg_v *gpos, const int *indep);
/* The generated acceleration stages' parameters (cg_acc_fn) and the arguments passing them on. */
#define CG_ACC_PARAMS                                                                           \
  "const double *g, const double *B, const double *Q, const double *h, const double *w, "      \
  "const double *N, const double *v, double *tk1, double *tk2, double *G, double *gB, "         \
  "double *Phi, double *edd, double *vdot, double *qdot"
#define CG_ACC_ARGS "g, B, Q, h, w, N, v, tk1, tk2, G, gB, Phi, edd, vdot, qdot"
/* The free speeds the generated acceleration stage is made for: k - b, or 0 when b >= k (every
 * speed fixed by the rows, as on a robot with prescribed wheel speeds). */
int cg_free_speeds(const ap_bmodel *M);

/* The stages' finiteness checks (apc_finite_pos, apc_finite_vel) and, when
 * cg_basis_supported, the partitioned basis and particular solution at the model's sizes
 * (apc_basis, apc_particular; emit_basis.c). */
int cg_basis_supported(const ap_bmodel *M);
/* The rank the generated basis is made for: min(b, k) (rows of full rank). */
int cg_basis_rank(int b, int k);
void cg_emit_basis(cg_gen *G, const ap_bmodel *M, const cg_v *gpos);

/* The whole translation unit for a model (emit_vel.c): NULL when out of memory. indep (k - b
 * ascending speeds, or NULL): the independent speeds of a partition expected at run time (the
 * scene's initial one); with it the source also has apc_acc_part, the acceleration stage for
 * that partition, which calls apc_acceleration for a state of another partition. */
char *cg_source(const ap_bmodel *M, const int *indep, char *why, size_t len);

/* ---- compile, cache, load (cache.c) ------------------------------------------------------ */

typedef int (*cg_plane_fn)(void *ctx, int joint, const double *Rj, double *z);
typedef int (*cg_drive_fn)(void *ctx, int joint);
typedef int (*cg_pos_fn)(const double *q, double *S, double *g, cg_plane_fn plane,
                         cg_drive_fn drive, void *ctx);
typedef void (*cg_vel_fn)(const double *v, double *S, double *h);
typedef int (*cg_acc_fn)(const double *g, const double *B, const double *Q, const double *h,
                         const double *w, const double *N, const double *v, double *tk1,
                         double *tk2, double *G, double *gB, double *Phi, double *edd,
                         double *vdot, double *qdot);

typedef int (*cg_finite_fn)(const double *a, const double *b, const double *c);
typedef int (*cg_basis_fn)(const int *perm, const double *A, const double *a0, double *F,
                           double *tau, double *B, double *b0, double *growth, double *resid);
typedef int (*cg_part_fn)(const int *perm, const double *F, const double *tau,
                          const double *gamma, double *w, double *resid);

typedef int (*cg_rows_fn)(const double *q, double *S, double *N, double *A, double *a0);
typedef void (*cg_forces_fn)(const double *v, double *S, double *Q, double *gamma);

typedef struct cg_lib {
  void *handle;
  cg_pos_fn position;
  cg_vel_fn velocity;
  cg_acc_fn acceleration;                /* apc_acc_part when there is one, else the generic */
  cg_finite_fn finite_pos, finite_vel;   /* 1: every output of the stage finite, <= AP_HUGE */
  cg_basis_fn basis;                     /* NULL when the model has none (no rows) */
  cg_part_fn particular;
  cg_rows_fn rows;                       /* apc_rows, apc_forces (emit_contact.c): NULL when */
  cg_forces_fn forces;                   /* absent; set by cg_rows_install, not by cg_load */
  double ms_compile;     /* wall time of the compiler run (0 from the cache) */
  int from_cache;
} cg_lib;

/* The shared object for src: from the cache when a valid one is there, else compiled and
 * cached. 0, or -1 with a one-line reason in why. */
int cg_load(const char *src, cg_lib *out, char *why, size_t len);

/* ---- contacts, N and gravity (emit_contact.c) and their run-time side (fast_rows.c) ------- */

/* What the generator takes: the wheel contacts' support points (all of them or none), a
 * constraint's rows and gamma, the effects (every one gravity). */
int cg_wheels_traced(const ap_bmodel *M);
int cg_con_traced(const ap_bmodel *M, int ci);
int cg_all_cons_traced(const ap_bmodel *M);
int cg_effects_traced(const ap_bmodel *M);
/* The plane contact's support point traced in place of the library's call (emit_kin.c): 1 when
 * done, 0 when the shape is not traced. */
int cg_plane_support(cg_kin *K, int jx, const cg_v *Rj, kjoint *J, cg_v *z);
/* apc_rows after the position stage, apc_forces after the velocity stage (cg_source). */
void cg_emit_rows(cg_kin *K);
void cg_emit_forces(cg_kin *K);

/* A compiled model's strategy (compiled.c): the model holds a pointer to base. */
typedef struct cg_fast {
  ap_bm_fast base;
  cg_lib lib;
  unsigned char *traced;   /* per constraint: rows and gamma generated (fast_rows.c) */
  int wheels, effects;     /* cg_wheels_traced, cg_effects_traced */
  int rest;                /* some row, or a wheel's geometry, is the library's */
} cg_fast;

/* Looks up apc_rows and apc_forces in the loaded object and installs them as the model's
 * rows and forces hooks (and the core's fills flags); without them the model keeps the
 * library's contacts, N and effects. AP_OK or AP_ERR_NOMEM. */
int cg_rows_install(ap_model *m, cg_fast *F);
/* ap_model_compile_native with the independent speeds of the partition expected at run time
 * (indep, k - b ascending, or NULL; compiled.c): the acceleration stage gets a variant for it. */
int cg_compile_hinted(const ap_model *m, ap_compile_mode mode, const int *indep, char *notice,
                      size_t len);
void cg_rows_free(cg_fast *F);

#endif
