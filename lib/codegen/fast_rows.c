/* The run-time side of emit_contact.c: the rest of a compiled model's position stage (after
 * apc_position) and velocity stage (after apc_velocity), in the order of hooks.c's
 * bm_position and bm_velocity. The generated apc_rows and apc_forces do the wheel contacts'
 * support points, N, the generated constraints' rows and gamma and gravity; the library does
 * the rest: the constraints the generator does not take (through their kind's table, each
 * writing its own rows), the time functions, the other effects and friction.
 *
 * When a disk or torus of a wheel contact lies flat the generated code stops and the library's
 * ap_contact_position runs, so that the run stops with its message. */
#include <dlfcn.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"
#include "model/con_friction.h"
#include "model/con_kind.h"

/* hooks.c's tail of bm_position, interpreted (after a flat wheel the library did not find). */
static int rows_interp(const ap_model *m, ap_data *d, double *S) {
  const ap_bmodel *M = ap_bm(m);
  int rc = M->nc ? ap_con_time(m, d, d->t, S) : AP_OK;
  if (rc != AP_OK) return rc;
  if (M->n != M->k) {
    memset(d->N, 0, sizeof(double) * (size_t)M->n * M->k);
    for (int j = 0; j < M->nj; j++) ap_joint_fill_N(&M->joints[j], d->q, d->N, M->n);
  }
  memset(d->A, 0, sizeof(double) * (size_t)M->b * M->k);
  memset(d->a0, 0, sizeof(double) * (size_t)M->b);
  return M->b ? ap_con_rows(m, d, d->t, d->q, S, d->A, d->a0) : AP_OK;
}

static int fast_rows(const ap_bm_fast *f, const ap_model *m, ap_data *d, double *S) {
  const cg_fast *F = (const cg_fast *)f;
  const ap_bmodel *M = ap_bm(m);
  int rc = AP_OK;
  if (F->lib.rows(d->q, S, d->N, d->A, d->a0) != 0) {   /* a wheel lies flat: the message */
    rc = ap_contact_position(m, d, d->t, S);
    return rc != AP_OK ? rc : rows_interp(m, d, S);
  }
  if (!F->rest) return AP_OK;   /* every row generated */
  if (M->nwheel && !F->wheels) rc = ap_contact_position(m, d, d->t, S);
  if (rc == AP_OK && M->nc) rc = ap_con_time(m, d, d->t, S);
  for (int ci = 0; ci < M->nc && rc == AP_OK; ci++)
    if (!F->traced[ci])
      rc = AP_CON_EVAL(&M->cons[ci])->rows(m, d, ci, d->t, d->q, S, d->A, d->a0);
  return rc;
}

static int fast_forces(const ap_bm_fast *f, const ap_model *m, ap_data *d, double *S) {
  const cg_fast *F = (const cg_fast *)f;
  const ap_bmodel *M = ap_bm(m);
  F->lib.forces(d->v, S, d->Q, d->gamma);
  if (!F->rest && F->effects && !M->nfric) return AP_OK;   /* all of it generated */
  int rc = M->ne && !F->effects ? ap_eff_forces(m, d, d->t, d->q, d->v, S, d->Q) : AP_OK;
  for (int ci = 0; ci < M->nc && rc == AP_OK; ci++)
    if (!F->traced[ci])
      rc = AP_CON_EVAL(&M->cons[ci])->gamma(m, d, ci, d->t, d->q, d->v, S, d->gamma);
  if (rc == AP_OK && M->nfric) rc = ap_cfr_friction(m, d, S);   /* sliding contacts */
  return rc;
}

int cg_rows_install(ap_model *m, cg_fast *F) {
  const ap_bmodel *M = ap_bm(m);
  F->lib.rows = (cg_rows_fn)(uintptr_t)dlsym(F->lib.handle, "apc_rows");
  F->lib.forces = (cg_forces_fn)(uintptr_t)dlsym(F->lib.handle, "apc_forces");
  if (!F->lib.rows || !F->lib.forces) return AP_OK;   /* the library's, as before */
  F->traced = calloc((size_t)M->nc + 1, 1);
  if (!F->traced) return AP_ERR_NOMEM;
  for (int ci = 0; ci < M->nc; ci++) F->traced[ci] = (unsigned char)cg_con_traced(M, ci);
  F->wheels = cg_wheels_traced(M), F->effects = cg_effects_traced(M);
  F->base.rows = fast_rows, F->base.forces = fast_forces;
  int all = cg_all_cons_traced(M);
  F->rest = !all || (M->nwheel && !F->wheels);
  m->ev.fills = (all ? AP_EV_FILLS_POSITION : 0) |
                (all && F->effects && !M->nfric ? AP_EV_FILLS_VELOCITY : 0);
  return AP_OK;
}

void cg_rows_free(cg_fast *F) {
  free(F->traced);
}
