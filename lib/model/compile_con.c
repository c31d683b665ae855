/* ap_builder_compile, part 2: the constraints (validated once; rows laid out in A).
 *
 * Each constraint gets its first row and row count in A, its implicit holonomic rows (loop
 * closures: all of them; a rolling or wheel knife-edge constraint on a body that is not on a
 * plane-contact joint: its last row, the contact row .z) and, for the latter, a wheel geometry
 * block in the scratch (contact.c). Row names: NAME, or NAME.x, NAME.y, NAME.z, NAME.spin,
 * NAME.side, NAME.n1, ... Every message names the constraint and the offending number. */
#include <stdio.h>
#include <string.h>

#include "model/builder.h"

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

static int finite_n(const double *x, int n) {
  for (int i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

/* ---- references and directions ------------------------------------------------------------ */

static int check_body_ref(ap_builder *b, const char *nm, const char *what, int body,
                          int ground_ok) {
  if ((ground_ok && body == AP_GROUND) || (body >= 0 && body < b->nb)) return AP_OK;
  FAIL("constraint '%s': %s %d does not exist (%d bodies%s)", nm, what, body, b->nb,
       ground_ok ? "; AP_GROUND allowed" : "");
}

static int check_ground(ap_builder *b, const char *nm, const ap_ground_motion *g) {
  if ((int)g->kind < 0 || (int)g->kind > 2)
    FAIL("constraint '%s': unknown ground kind %d", nm, (int)g->kind);
  if (!finite_n(g->center, 2) || !isfinite(g->omega) || !finite_n(g->velocity, 2))
    FAIL("constraint '%s': the ground motion has a non-finite parameter", nm);
  return AP_OK;
}

/* Unit normals n1, n2 of the unit direction t. */
static void normals_of(const double *t, double *n1, double *n2) {
  double e[3] = {0, 0, 0};
  int i = fabs(t[0]) <= fabs(t[1]) && fabs(t[0]) <= fabs(t[2]) ? 0
          : fabs(t[1]) <= fabs(t[2])                         ? 1
                                                              : 2;
  e[i] = 1.0;
  v3_cross(t, e, n1);
  double nn = v3_norm(n1);
  for (int k = 0; k < 3; k++) n1[k] /= nn;
  v3_cross(t, n1, n2);
}

static int unit_direction(ap_builder *b, const char *nm, const double *dir, double *out) {
  double n = v3_norm(dir);
  if (!(n > 1e-12) || !finite_n(dir, 3))
    FAIL("constraint '%s': direction (%g, %g, %g) is zero or not finite", nm, dir[0], dir[1],
         dir[2]);
  for (int i = 0; i < 3; i++) out[i] = dir[i] / n;
  return AP_OK;
}

static int compile_speed(ap_builder *b, const ap_bmodel *M, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  if (d->joint < 0 || d->joint >= b->nj)
    FAIL("constraint '%s': joint %d does not exist (%d joints)", nm, d->joint, b->nj);
  const ap_mjoint *J = &M->joints[M->joint_topo[d->joint]];
  if (d->speed < 0 || d->speed >= J->nv)
    FAIL("constraint '%s': joint '%s' has %d speeds, not speed %d", nm, J->name, J->nv, d->speed);
  if (J->vidx[d->speed] < 0)
    FAIL("constraint '%s': speed %d of joint '%s' is driven (eliminated) already", nm, d->speed,
         J->name);
  if (!isfinite(d->speed_value)) FAIL("constraint '%s': speed_value is not finite", nm);
  c->col = J->vidx[d->speed], c->nrows = 1, c->timed = 1;
  return AP_OK;
}

static int compile_loop(ap_builder *b, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  int rc = check_body_ref(b, nm, "body", d->body, 0);
  if (rc == AP_OK) rc = check_body_ref(b, nm, "body2", d->body2, 1);
  if (rc != AP_OK) return rc;
  if (d->body == d->body2) FAIL("constraint '%s': body and body2 are the same body", nm);
  if (!finite_n(d->point, 3) || !finite_n(d->point2, 3))
    FAIL("constraint '%s': points not finite", nm);
  if (d->kind == AP_CON_COINCIDENT) {
    if ((d->axes & 7u) == 0 || (d->axes & ~7u))
      FAIL("constraint '%s': axes mask %u is not a set of world axes (bits 1 = x, 2 = y, "
           "4 = z)", nm, d->axes);
    c->nrows = (int)((d->axes & 1u) + ((d->axes >> 1) & 1u) + ((d->axes >> 2) & 1u));
    return AP_OK;
  }
  rc = unit_direction(b, nm, d->direction, c->dir);
  if (d->kind == AP_CON_POINT_ON_LINE) normals_of(c->dir, c->n1, c->n2);
  c->nrows = d->kind == AP_CON_POINT_ON_LINE ? 2 : 1;
  return rc;
}

/* Rolling, or a wheel's knife edge: the shape's lowest point touches the ground. On a
 * plane-contact joint the joint holds it there; on any other joint the constraint adds the
 * contact row .z (last row, holonomic) and a geometry block of its own. */
static int compile_wheel(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  const ap_mbody *B = &M->bodies[d->body];
  const ap_mjoint *J = &M->joints[B->joint];
  ap_shape_kind sk = B->shape.kind;
  int knife = d->kind == AP_CON_KNIFE_EDGE;
  if (knife && sk != AP_SHAPE_DISK && sk != AP_SHAPE_TORUS)
    FAIL("constraint '%s': a wheel knife edge needs body '%s' to be a disk or a torus (its "
         "shape kind is %d): the wheel plane is its body xy plane", nm, B->name, (int)sk);
  if (sk == AP_SHAPE_NONE)
    FAIL("constraint '%s': rolling needs body '%s' to have a shape (sphere, ellipsoid, disk, "
         "torus or point) touching the ground plane", nm, B->name);
  if (!knife && d->wheel)
    FAIL("constraint '%s': wheel = %d belongs to a knife edge (rolling always uses the shape's "
         "contact point)", nm, d->wheel);
  c->nrows = knife ? 1 : d->no_spin ? 3 : 2;
  c->wheel = -1;
  if (J->kind == AP_JOINT_PLANE_CONTACT) return AP_OK;
  c->wheel = M->nwheel++;
  c->hrow = c->nrows++;
  c->nhol = 1;
  return AP_OK;
}

static int compile_contact(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  int rc = check_body_ref(b, nm, "body", d->body, 0);
  if (rc == AP_OK) rc = check_ground(b, nm, &d->ground);
  if (rc != AP_OK) return rc;
  c->timed = d->ground.kind != AP_GROUND_FIXED;
  if (d->kind == AP_CON_KNIFE_EDGE && !d->wheel) {
    if (!finite_n(d->point, 3)) FAIL("constraint '%s': point not finite", nm);
    c->nrows = 1;
    return unit_direction(b, nm, d->direction, c->dir);
  }
  return compile_wheel(b, M, nm, c);
}

int ap_compile_constraints(ap_builder *b, ap_bmodel *M) {
  int row = 0;
  for (int i = 0; i < b->nc; i++) {
    ap_mcon *c = &M->cons[i];
    const char *nm = b->cons[i].name;
    int rc = AP_OK;
    snprintf(c->name, sizeof c->name, "%s", nm);
    c->def = b->cons[i].def;
    c->wheel = -2;
    switch (c->def.kind) {
      case AP_CON_ROLLING:
      case AP_CON_KNIFE_EDGE: rc = compile_contact(b, M, nm, c); break;
      case AP_CON_PRESCRIBED_SPEED: rc = compile_speed(b, M, nm, c); break;
      case AP_CON_USER:
        if (c->def.rows < 1 || !c->def.user_constraint || !c->def.user_gamma)
          FAIL("constraint '%s': a user constraint needs rows >= 1 (got %d) and both "
               "user_constraint and user_gamma", nm, c->def.rows);
        c->nrows = c->def.rows;
        M->max_user_rows = c->nrows > M->max_user_rows ? c->nrows : M->max_user_rows;
        break;
      case AP_CON_COINCIDENT:
      case AP_CON_POINT_ON_LINE:
      case AP_CON_POINT_ON_PLANE:
        rc = compile_loop(b, nm, c);
        c->nhol = c->nrows;
        break;
      default: FAIL("constraint '%s': unknown kind %d", nm, (int)c->def.kind);
    }
    if (rc != AP_OK) return rc;
    c->row = row;
    row += c->nrows;
    M->nloop += c->nhol;
    M->lscale = fmax(M->lscale, fmax(v3_norm(c->def.point), v3_norm(c->def.point2)));
  }
  M->b = row;
  return AP_OK;
}

/* ---- row names ---------------------------------------------------------------------------- */

const char *ap_con_row_suffix(const ap_mcon *c, int r, char *buf) {
  static const char *const xyz[] = {".x", ".y", ".z"};
  switch (c->def.kind) {
    case AP_CON_ROLLING: return r < 2 ? xyz[r] : r == c->hrow && c->nhol ? ".z" : ".spin";
    case AP_CON_KNIFE_EDGE: return !c->def.wheel ? "" : r == 0 ? ".side" : ".z";
    case AP_CON_POINT_ON_LINE: return r ? ".n2" : ".n1";
    case AP_CON_COINCIDENT:
      for (int a = 0, seen = 0; a < 3; a++)
        if (c->def.axes & (1u << a) && seen++ == r) return xyz[a];
      return "";
    case AP_CON_USER: snprintf(buf, 16, ".%d", r); return buf;
    default: return "";
  }
}

