/* ap_builder_compile, part 2: the constraints (validated once; rows laid out in A).
 *
 * Each constraint gets its kind's table of operations (con_kind.h), which validates it and
 * sets its row count, its implicit holonomic rows (loop closures: all of them; a rolling or
 * wheel knife-edge constraint on a body that is not on a plane-contact joint: its last row,
 * the contact row .z) and, for the latter, a wheel geometry block in the scratch (contact.c);
 * then its first row in A. Row names: NAME, or NAME.x, NAME.y, NAME.z, NAME.spin, NAME.side,
 * NAME.n1, ... (the kind's suffix). Every message names the constraint and the offending
 * number. */
#include <stdio.h>
#include <string.h>

#include "model/builder.h"
#include "model/con_kind.h"

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

int ap_cc_finite(const double *x, int n) {
  for (int i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

int ap_cc_body_ref(ap_builder *b, const char *nm, const char *what, int body, int ground_ok) {
  if ((ground_ok && body == AP_GROUND) || (body >= 0 && body < b->nb)) return AP_OK;
  FAIL("constraint '%s': %s %d does not exist (%d bodies%s)", nm, what, body, b->nb,
       ground_ok ? "; AP_GROUND allowed" : "");
}

int ap_cc_ground(ap_builder *b, const char *nm, const ap_ground_motion *g) {
  if ((int)g->kind < 0 || (int)g->kind > 2)
    FAIL("constraint '%s': unknown ground kind %d", nm, (int)g->kind);
  if (!ap_cc_finite(g->center, 2) || !isfinite(g->omega) || !ap_cc_finite(g->velocity, 2) ||
      !ap_cc_finite(g->normal, 3) || !isfinite(g->offset))
    FAIL("constraint '%s': the ground motion has a non-finite parameter", nm);
  return AP_OK;
}

int ap_cc_unit_direction(ap_builder *b, const char *nm, const double *dir, double *out) {
  double n = v3_norm(dir);
  if (!(n > 1e-12) || !ap_cc_finite(dir, 3))
    FAIL("constraint '%s': direction (%g, %g, %g) is zero or not finite", nm, dir[0], dir[1],
         dir[2]);
  for (int i = 0; i < 3; i++) out[i] = dir[i] / n;
  return AP_OK;
}

int ap_compile_constraints(ap_builder *b, ap_bmodel *M) {
  int row = 0;
  for (int i = 0; i < b->nc; i++) {
    ap_mcon *c = &M->cons[i];
    const char *nm = b->cons[i].name;
    snprintf(c->name, sizeof c->name, "%s", nm);
    c->def = b->cons[i].def;
    c->wheel = -2;
    c->fric = -1;
    if ((int)c->def.kind < 0 || (int)c->def.kind >= AP_CON_NKINDS)
      FAIL("constraint '%s': unknown kind %d", nm, (int)c->def.kind);
    c->kind = ap_con_kinds[c->def.kind];
    int rc = c->kind->compile(b, M, nm, c);
    if (rc != AP_OK) return rc;
    c->row = row;
    row += c->nrows;
    M->nloop += c->nhol;
    M->lscale = fmax(M->lscale, fmax(v3_norm(c->def.point), v3_norm(c->def.point2)));
  }
  M->b = row;
  return AP_OK;
}

const char *ap_con_row_suffix(const ap_mcon *c, int r, char *buf) {
  return c->kind->suffix(c, r, buf);
}
