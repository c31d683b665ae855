/* A height-field ground in a scene (docs/scenes.md "Terrain"):
 *
 *     ground: {kind: height_field, z: "0.05*exp(-((x-1)^2 + y^2)/0.1)"}
 *
 * `z` is an expression of the world coordinates x and y (m; the scene's parameters allowed,
 * not t). The model layer asks for h and its first and second partial derivatives
 * (ap_height_fn); they come exactly from the expression's second-order Taylor jets (expr.h):
 * seeding x gives (h, h_x, h_xx / 2), seeding y gives h_y and h_yy, and seeding both gives
 * the second derivative along (1, 1), h_xx + 2 h_xy + h_yy, hence h_xy. */
#include <string.h>

#include "scene/scene_int.h"

static const char *const xy_names[] = {"x", "y", NULL};

static int compile_z(sc_ctx *c, const sc_node *z, const char *text, sc_expr *e) {
  sc_symtab sym = {0, xy_names, NULL, NULL, NULL, NULL};
  return sc_expr_compile_sym(c, z, text, &sym, e);
}

int sc_parse_height(sc_ctx *c, const sc_node *n, sc_ground *g) {
  static const char *const others[] = {"center", "omega", "velocity", "normal", "offset",
                                       "sphere", NULL};
  const char *kind = NULL;
  if (sc_get_name(c, n, "kind", &kind)) return AP_ERR_ARG;
  const sc_node *z = sc_map_get(n, "z");
  if (!kind || strcmp(kind, "height_field") != 0)
    return sc_err(c, z, "z (a height z = h(x, y)) belongs to a height-field ground (kind: "
                  "height_field)");
  if (!z) return sc_err(c, n, "a height-field ground needs z: an expression of x and y (m)");
  for (int i = 0; others[i]; i++)
    if (sc_map_get(n, others[i]))
      return sc_err(c, sc_map_get(n, others[i]), "a height-field ground is fixed and given by z "
                    "alone: %s does not belong to it", others[i]);
  if (sc_expect(c, z, SC_SCALAR) || compile_z(c, z, z->text, &g->height)) return AP_ERR_ARG;
  g->def.kind = AP_GROUND_FIXED;
  g->def.height_fn = sc_height_fn;
  return AP_OK;
}

int sc_height_copy(sc_ctx *c, const sc_ground *from, sc_ground *to) {
  if (!from->def.height_fn) return AP_OK;
  to->height.value = from->height.value, to->height.node = from->height.node;
  if (!from->height.timed) return AP_OK;
  return compile_z(c, from->height.node, from->height.text, &to->height);
}

/* The jet of h along (dx, dy) at (x, y): (h, directional derivative, half the second). */
static int jet(const sc_expr *e, double x, double y, double dx, double dy, sc_jet *f) {
  sc_jet t = {{0.0, 0.0, 0.0}}, xy[2] = {{{x, dx, 0.0}}, {{y, dy, 0.0}}};
  return sc_prog_jet(e->prog, &t, xy, f);
}

int sc_height_fn(double x, double y, double h[6], void *user) {
  const sc_expr *e = user;
  memset(h, 0, 6 * sizeof *h);
  if (!e->timed) return h[0] = e->value, 0;
  sc_jet fx, fy, fd;
  int rc = jet(e, x, y, 1.0, 0.0, &fx) | jet(e, x, y, 0.0, 1.0, &fy) |
           jet(e, x, y, 1.0, 1.0, &fd);
  h[0] = fx.c[0], h[1] = fx.c[1], h[2] = fy.c[1];
  h[3] = 2.0 * fx.c[2], h[5] = 2.0 * fy.c[2];
  h[4] = fd.c[2] - fx.c[2] - fy.c[2];   /* (h_xx + 2 h_xy + h_yy) / 2 - h_xx / 2 - h_yy / 2 */
  return rc ? -1 : 0;
}
