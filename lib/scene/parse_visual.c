/* A body's visual-only shape (bodies: NAME: visual:), drawn by `appell view` and exported by
 * `appell export`, ignored by the dynamics (docs/scenes.md "bodies"):
 *
 *   visual: {kind: box, size: [lx, ly, lz], at: [x, y, z]}          edge lengths (m)
 *   visual: {kind: capsule, radius: r, length: l, axis: z, at: ...}  cylinder of length l plus
 *                                                                    two half-spheres
 *   visual: {kind: sphere, radius: r, at: ...}
 *
 * `at` is the shape's centre in body axes (default the body origin). */
#include <string.h>

#include "scene/scene_int.h"

static const char *const visual_keys[] = {"kind", "size", "radius", "length", "axis", "at",
                                          NULL};
static const char *const visual_kinds[] = {"none", "box", "capsule", "sphere", NULL};
static const char *const axes[] = {"x", "y", "z", NULL};

static int check_size(sc_ctx *c, const sc_node *n, const ap_scene_visual *v) {
  for (int i = 0; v->kind == AP_VISUAL_BOX && i < 3; i++)
    if (!(v->size[i] > 0))
      return sc_err(c, sc_map_get(n, "size") ? sc_map_get(n, "size") : n,
                    "a box visual needs size: three positive edge lengths (entry %d is %g)", i,
                    v->size[i]);
  if ((v->kind == AP_VISUAL_CAPSULE || v->kind == AP_VISUAL_SPHERE) &&
      sc_check_positive(c, n, "radius", v->radius))
    return AP_ERR_ARG;
  if (v->kind == AP_VISUAL_CAPSULE && sc_check_nonneg(c, n, "length", v->length))
    return AP_ERR_ARG;
  return AP_OK;
}

int sc_parse_visual(sc_ctx *c, const sc_node *n, ap_scene_visual *v) {
  memset(v, 0, sizeof *v);
  v->axis = 2;
  int kind = 0;
  if (sc_check_keys(c, n, visual_keys)) return AP_ERR_ARG;
  if (!sc_map_get(n, "kind"))
    return sc_err(c, n, "the visual needs a kind (box, capsule, sphere or none)");
  if (sc_get_enum(c, n, "kind", visual_kinds, &kind) || sc_get_vec(c, n, "size", 3, v->size) ||
      sc_get_number(c, n, "radius", &v->radius) || sc_get_number(c, n, "length", &v->length) ||
      sc_get_enum(c, n, "axis", axes, &v->axis) || sc_get_vec(c, n, "at", 3, v->at))
    return AP_ERR_ARG;
  v->kind = (ap_visual_kind)kind;
  return check_size(c, n, v);
}
