/* Compiled models (appell/compiled.h): generate the model's code (emit_kin.c, emit_vel.c),
 * get its shared object (cache.c) and install it as the body model's fast kinematics
 * (model/model.h ap_bm_fast), which the position and velocity hooks call in place of
 * ap_kin_position + ap_kin_metric and ap_kin_velocity + ap_kin_bias, and the rest of both
 * stages (contacts, N, rows, gravity, gamma: fast_rows.c). The plane contact's support function
 * is called back into the library (ap_kin_plane) to report a shape lying flat. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/compiled.h"
#include "codegen/codegen.h"
#include "linalg/linalg.h"

typedef struct plane_ctx {
  const ap_model *m;
  ap_data *d;
  double *S;
} plane_ctx;

static int plane_cb(void *ctx, int joint, const double *Rj, double *z) {
  plane_ctx *c = ctx;
  return ap_kin_plane(c->m, c->d, joint, c->d->t, Rj, c->S, z);
}

static int drive_cb(void *ctx, int joint) {
  plane_ctx *c = ctx;
  return ap_kin_drives(c->m, c->d, joint, c->d->t, c->S);
}

static int fast_position(const ap_bm_fast *f, const ap_model *m, ap_data *d, double *S) {
  plane_ctx c = {m, d, S};
  return ((const cg_fast *)f)->lib.position(d->q, S, d->g, plane_cb, drive_cb, &c);
}

static void fast_velocity(const ap_bm_fast *f, const double *v, double *S, double *h) {
  ((const cg_fast *)f)->lib.velocity(v, S, h);
}

/* The compiled acceleration stage where the core would run its native kernels on the model's
 * sizes with the same free speeds and no condition estimate (forward.c fwd_acceleration): the
 * variant for the expected partition when the model has one (it goes on to the generic stage
 * for another partition, cache.c). */
static int fast_acceleration(const ap_model *m, ap_data *d) {
  const cg_fast *F = (const cg_fast *)ap_bm(m)->fast;
  int k = m->k, lim = ap_la_small_limit();
  if (!F || d->estimate_cond || d->l != cg_free_speeds(ap_bm(m)) || k > lim || m->n > lim)
    return AP_ERR_UNSUPPORTED;
  ap_scratch *s = (ap_scratch *)d->internal;
  int rc = F->lib.acceleration(d->g, d->B, d->Q, d->h, d->w, d->N, d->v, s->tk1, s->tk2, d->G,
                               s->gB, d->Phi, d->edd, d->vdot, d->qdot);
  return rc == 0 ? AP_OK : AP_ERR_UNSUPPORTED;
}

/* The stage's one finiteness check (emit_basis.c). When it fails, the stage runs again
 * interpreted (zeroed as the core zeroes it), so that the core's per-array checks find the
 * entry the interpreted path finds: a NaN reaches entries the compiled code never computes
 * (a product with a structural zero, folded away) in the interpreted code only. */
static int fast_finite(const ap_model *m, ap_data *d, int stage) {
  const cg_lib *L = &((const cg_fast *)ap_bm(m)->fast)->lib;
  double *S = ((ap_scratch *)d->internal)->ev;
  size_t k = (size_t)m->k, b = (size_t)m->b;
  if (stage == 0) {
    if (L->finite_pos(d->g, d->A, d->a0)) return 1;
    memset(d->g, 0, sizeof(double) * k * k);
    if (m->n != m->k) memset(d->N, 0, sizeof(double) * (size_t)m->n * k);
    memset(d->A, 0, sizeof(double) * b * k), memset(d->a0, 0, sizeof(double) * b);
    (void)ap_bm_position_interp(m, d, S);
    return 0;
  }
  if (L->finite_vel(d->h, d->Q, d->gamma)) return 1;
  memset(d->h, 0, sizeof(double) * k), memset(d->Q, 0, sizeof(double) * k);
  memset(d->gamma, 0, sizeof(double) * b);
  (void)ap_bm_velocity_interp(m, d, S);
  return 0;
}

/* The generated basis where the library's ap_la_partition_basis would run its native kernels
 * on rows of full rank (r = min(b, k)); otherwise, and on any number the generated code does
 * not take, the library's routine runs. */
static int basis_taken(const ap_model *m, const ap_data *d) {
  int lim = ap_la_small_limit();
  return d->rank == cg_basis_rank(m->b, m->k) && m->k <= lim && m->b <= lim;
}

static int fast_basis(const ap_model *m, ap_data *d, double *resid) {
  const cg_lib *L = &((const cg_fast *)ap_bm(m)->fast)->lib;
  ap_scratch *s = (ap_scratch *)d->internal;
  if (!basis_taken(m, d) ||
      L->basis(d->perm, d->A, d->a0, s->F, s->tau, d->B, d->b0, &d->growth, resid) != 0)
    return AP_ERR_UNSUPPORTED;
  return AP_OK;
}

static int fast_particular(const ap_model *m, ap_data *d) {
  const cg_lib *L = &((const cg_fast *)ap_bm(m)->fast)->lib;
  ap_scratch *s = (ap_scratch *)d->internal;
  if (!basis_taken(m, d) || L->particular(d->perm, s->F, s->tau, d->gamma, d->w,
                                          &d->resid_gamma) != 0)
    return AP_ERR_UNSUPPORTED;
  return AP_OK;
}

static void fast_destroy(ap_bm_fast *f) {
  cg_fast *F = (cg_fast *)f;
  if (F->lib.handle) dlclose(F->lib.handle);
  cg_rows_free(F);
  free(F);
}

int ap_compile_mode_parse(const char *name, ap_compile_mode *mode) {
  static const char *const names[] = {"never", "auto", "always"};
  for (int i = 0; name && mode && i < 3; i++)
    if (strcmp(name, names[i]) == 0) return *mode = (ap_compile_mode)i, AP_OK;
  return AP_ERR_ARG;
}

int ap_model_is_compiled(const ap_model *m) {
  return ap_model_is_body_model(m) && ap_bm(m)->fast != NULL;
}

static int why_not(const ap_model *m, char *why, size_t len) {
  if (!ap_model_is_body_model(m))
    return snprintf(why, len, "it is not a body model (a math-level system)"), -1;
  if (m->ops) return snprintf(why, len, "it runs on the tree path, which is not compiled"), -1;
  return cg_kin_supported(ap_bm(m), why, len);
}

int ap_model_compile_native(const ap_model *m, ap_compile_mode mode, char *notice,
                            size_t len) {
  return cg_compile_hinted(m, mode, NULL, notice, len);
}

int cg_compile_hinted(const ap_model *m, ap_compile_mode mode, const int *indep, char *notice,
                      size_t len) {
  char why[512] = "", dummy[1];
  if (!notice) notice = dummy, len = sizeof dummy;
  if (len) notice[0] = '\0';
  if (!m || (int)mode < AP_COMPILE_NEVER || (int)mode > AP_COMPILE_ALWAYS) return AP_ERR_ARG;
  if (mode == AP_COMPILE_NEVER) return 0;
  if (ap_model_is_compiled(m)) return 1;
  char *src = why_not(m, why, sizeof why) == 0 ? cg_source(ap_bm(m), indep, why, sizeof why) : NULL;
  cg_fast *F = src ? calloc(1, sizeof *F) : NULL;
  if (src && !F) snprintf(why, sizeof why, "out of memory");
  int rc = F ? cg_load(src, &F->lib, why, sizeof why) : -1;
  free(src);
  if (rc != 0) {
    free(F);
    snprintf(notice, len, "appell: model '%s' runs interpreted: %s", m->name, why);
    return 0;
  }
  F->base.position = fast_position, F->base.velocity = fast_velocity;
  F->base.destroy = fast_destroy;
  if (cg_rows_install((ap_model *)m, F) != AP_OK) {   /* contacts, N, gravity (fast_rows.c) */
    fast_destroy(&F->base);
    snprintf(notice, len, "appell: model '%s' runs interpreted: out of memory", m->name);
    return 0;
  }
  ((ap_bmodel *)ap_bm(m))->fast = &F->base;   /* the model's evaluation strategy */
  ((ap_model *)m)->ev.acceleration = fast_acceleration;
  ((ap_model *)m)->ev.finite = fast_finite;
  if (F->lib.basis) {
    ((ap_model *)m)->ev.basis = fast_basis;
    ((ap_model *)m)->ev.particular = fast_particular;
  }
  return 1;
}
