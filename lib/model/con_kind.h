/* Appell body layer (internal): one table of operations per constraint kind.
 *
 * A constraint kind is one file (con_*.c, or contact.c for the contacts with the ground) that
 * defines one ap_con_kind: what compile, the row names, the forces on a subtree, the tree path
 * and the complex-step build need, each an entry of the table, and no switch elsewhere. The
 * per-evaluation operations (time functions, rows of A and a0, gamma, implicit holonomic rows)
 * are generic in the scalar (linalg/scalar.h): the kind's file is compiled twice and each build
 * defines its evaluation table, AP_SC(ap_con_xxx_eval); the kind table (double build) points at
 * both. A compiled constraint holds its kind table (ap_mcon.kind); the public kind
 * (ap_constraint_kind) picks the first one from ap_con_kinds (constraint.c) and the kind's
 * compile may hand the constraint to a variant (a knife edge with def.wheel becomes a wheel
 * knife edge).
 *
 * Adding a kind: its file with the two tables, one row of ap_con_kinds, the public enum value,
 * and the scene reader's name and keys (lib/scene/parse_con.c). */
#ifndef AP_MODEL_CON_KIND_H
#define AP_MODEL_CON_KIND_H

#include "model/model.h"

/* Per-evaluation operations (this build's scalar). Every entry may be NULL where the kind has
 * no such rows: time (only the ground motion, constraint.c), hol (no implicit holonomic
 * rows). ci is the constraint's index in M->cons, G its time scratch (CON_STRIDE, zero-filled
 * before time is called). rows writes rows c->row.. of A (ld M->b) and a0; gamma the same rows
 * of gamma; hol returns the residual of implicit holonomic row r (c->hrow <= r < c->hrow +
 * c->nhol) and its K1 coefficients of [v; 1] in row. */
typedef struct AP_SC(ap_con_eval) {
  int (*time)(const ap_model *m, ap_data *d, const ap_mcon *c, double t, ap_sc *G);
  int (*rows)(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, ap_sc *S,
              ap_sc *A, ap_sc *a0);
  int (*gamma)(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, const ap_sc *v,
               ap_sc *S, ap_sc *gamma);
  ap_sc (*hol)(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int r, ap_sc *row);
} AP_SC(ap_con_eval);

struct ap_con_eval;
struct ap_con_eval_cs;
struct ap_tplan;

/* The kind table (double build). compile validates c->def (builder messages name the
 * constraint nm) and sets c->nrows, and where they apply c->nhol, c->hrow, c->wheel, c->dir,
 * c->col, c->timed; it may replace c->kind by a variant. suffix names row r ("", ".x", ...; buf
 * 16 chars). wrench adds to F (and to T, moments about the world point o) the force of the
 * constraint's rows with multipliers lam on the bodies of the subtree rooted at root (after
 * the position stage; AP_ERR_UNSUPPORTED when it cannot be attributed to bodies). tree_body
 * gives the body its rows live on for the tree path, or -1 with the reason in why; tree_row
 * writes the covector cv (6: on the body twist (w; v) at the body origin) and a0 of its row
 * rr from the shadow's scratch S, the time scratch G and the body's rheonomic twist rho
 * (tree_eval.c). no_cs: why the complex-step build cannot evaluate the kind, or NULL. contact:
 * a contact with the ground whose force ap_body_contact_force reports. */
typedef struct ap_con_kind {
  const char *name;
  int (*compile)(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c);
  const char *(*suffix)(const ap_mcon *c, int r, char *buf);
  int (*wrench)(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam, int root,
                const double *o, double *F, double *T);
  int (*tree_body)(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                   size_t len);
  void (*tree_row)(const ap_bmodel *Ms, double *S, const ap_mcon *c, int rr, const double *G,
                   const double *rho, double *cv, double *a0);
  const char *no_cs;
  int contact;
  const struct ap_con_eval *eval;
  const struct ap_con_eval_cs *eval_cs;
} ap_con_kind;

/* This build's evaluation table of a compiled constraint. */
#define AP_CON_EVAL(c) ((const AP_SC(ap_con_eval) *)(c)->kind->AP_SC(eval))

/* The constraint's time scratch (CON_STRIDE). */
static inline ap_sc *ap_con_scratch(const ap_bmodel *M, ap_sc *S, int ci) {
  return S + M->off_con + (size_t)ci * CON_STRIDE;
}

/* Slots of the time scratch: ground motion (constraint.c) and a prescribed value f, f'. */
enum { AP_G_VX = 2, AP_G_VY, AP_G_DVX, AP_G_DVY, AP_G_F, AP_G_FD };

/* Row r of A and a0 from the K1 coefficients J (c3 == NULL: J[col * stride]; else c3 . J[:,
 * col]) minus a free velocity term (constraint.c). */
static inline void ap_con_put_row(const ap_bmodel *M, ap_sc *A, ap_sc *a0, int r,
                                  const ap_sc *c3, const ap_sc *J, int stride, ap_sc minus) {
  int k = M->k, b = M->b;
  for (int col = 0; col <= k; col++) {
    ap_sc s = c3 ? v3_dot(c3, J + 3 * col) : J[(size_t)col * stride];
    if (col < k) A[r + (size_t)col * b] = s;
    else a0[r] = s - minus;
  }
}

/* A time function f(t) of constraint c into f (3: value, rate, acceleration), its failure
 * reported as `what` (constraint.c). */
#define ap_con_time_call AP_SC(ap_con_time_call)
int ap_con_time_call(const ap_model *m, ap_data *d, const ap_mcon *c, const char *what,
                     ap_time_fn fn, void *user, double t, double *f);

/* ---- the kinds (double build) -------------------------------------------------------------- */
#ifndef AP_SC_COMPLEX
extern const ap_con_kind ap_con_rolling, ap_con_wheel_knife, ap_con_knife, ap_con_speed,
    ap_con_user, ap_con_coincident, ap_con_on_line, ap_con_on_plane;
/* By public kind (ap_constraint_kind), AP_CON_NKINDS entries. */
#define AP_CON_NKINDS 7
extern const ap_con_kind *const ap_con_kinds[AP_CON_NKINDS];

/* Compile helpers shared by the kinds (compile_con.c). */
int ap_cc_body_ref(ap_builder *b, const char *nm, const char *what, int body, int ground_ok);
int ap_cc_ground(ap_builder *b, const char *nm, const ap_ground_motion *g);
int ap_cc_unit_direction(ap_builder *b, const char *nm, const double *dir, double *out);
int ap_cc_finite(const double *x, int n);
/* Tree path: the covector and a0 of the row n . (vP - Vg(x)) at the body point with offset r
 * (world) from the body origin o (constraint.c). */
void ap_con_tree_point_row(const ap_mcon *c, const double *G, const double *o, const double *r,
                           const double *n, const double *rho, double *cv, double *a0);
#endif

#endif
