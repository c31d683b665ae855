/* Constraint kind: user constraints, `rows` rows from C callbacks for A, a0 and gamma over
 * every speed. Their forces cannot be attributed to bodies, the tree path cannot take them
 * (rows over every speed), and the callbacks are C functions of doubles: the complex-step
 * build refuses the model by name (ev.cs_blocker). Callback scratch: the tail of the
 * constraint assembly scratch. */
#include <stdio.h>
#include <string.h>

#include "model/builder.h"
#include "model/con_kind.h"

#ifdef AP_SC_COMPLEX
/* A user constraint's callbacks are C functions of doubles: no complex-step evaluation. */
static int user_cs(const ap_model *m, ap_data *d, int ci) {
  AP_BM_MSG(d, "model '%s': constraint '%s': a user constraint (C callbacks of doubles) has no "
            "complex-step evaluation", m->name, ap_bm(m)->cons[ci].name);
  return AP_ERR_UNSUPPORTED;
}
static int user_rows(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, ap_sc *S,
                     ap_sc *A, ap_sc *a0) {
  (void)t, (void)q, (void)S, (void)A, (void)a0;
  return user_cs(m, d, ci);
}
static int user_gamma(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                      const ap_sc *v, ap_sc *S, ap_sc *gamma) {
  (void)t, (void)q, (void)v, (void)S, (void)gamma;
  return user_cs(m, d, ci);
}
#else
static int user_rows(const ap_model *m, ap_data *d, int ci, double t, const double *q,
                     double *S, double *A, double *a0) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  int nr = c->nrows, k = M->k;
  double *Au = S + M->off_tmp + 6 * (size_t)M->K1 + 2 * (size_t)k, *au = Au + (size_t)nr * k;
  memset(Au, 0, (size_t)nr * (k + 1) * sizeof *Au);
  int rc = c->def.user_constraint(t, q, Au, au, c->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': constraint '%s': the user constraint callback %s (returned %d) "
              "at t = %.17g", m->name, c->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  for (int r = 0; r < nr; r++) {
    for (int col = 0; col < k; col++) A[c->row + r + (size_t)col * M->b] = Au[r + (size_t)col * nr];
    a0[c->row + r] = au[r];
  }
  return AP_OK;
}
static int user_gamma(const ap_model *m, ap_data *d, int ci, double t, const double *q,
                      const double *v, double *S, double *gamma) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  double *gu = S + M->off_tmp + 6 * (size_t)M->K1 + 2 * (size_t)M->k;
  memset(gu, 0, (size_t)c->nrows * sizeof *gu);
  int rc = c->def.user_gamma(t, q, v, gu, c->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': constraint '%s': the user gamma callback %s (returned %d) at "
              "t = %.17g", m->name, c->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  memcpy(gamma + c->row, gu, (size_t)c->nrows * sizeof *gu);
  return AP_OK;
}
#endif

const AP_SC(ap_con_eval) AP_SC(ap_con_user_eval) = {NULL, user_rows, user_gamma, NULL};

/* ---- double build: the kind table --------------------------------------------------------- */
#ifndef AP_SC_COMPLEX
extern const struct ap_con_eval_cs ap_con_user_eval_cs;

static int user_compile(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  if (c->def.rows < 1 || !c->def.user_constraint || !c->def.user_gamma)
    return ap_builder_fail(b, "constraint '%s': a user constraint needs rows >= 1 (got %d) and "
                           "both user_constraint and user_gamma", nm, c->def.rows);
  c->nrows = c->def.rows;
  M->max_user_rows = c->nrows > M->max_user_rows ? c->nrows : M->max_user_rows;
  return AP_OK;
}

static const char *user_suffix(const ap_mcon *c, int r, char *buf) {
  (void)c;
  snprintf(buf, 16, ".%d", r);
  return buf;
}

static int user_wrench(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                       int root, const double *o, double *F, double *T) {
  (void)M, (void)S, (void)c, (void)lam, (void)root, (void)o, (void)F, (void)T;
  return AP_ERR_UNSUPPORTED;
}

static int user_tree_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                          size_t len) {
  (void)M;
  snprintf(why, len, "model '%s': constraint '%s' is a user constraint (rows over every "
           "speed)", m->name, c->name);
  return -1;
}

const ap_con_kind ap_con_user = {"user", user_compile, user_suffix, user_wrench, user_tree_body,
                                 NULL, "a user constraint (C callbacks of doubles)", 0,
                                 &ap_con_user_eval, &ap_con_user_eval_cs};
#endif
