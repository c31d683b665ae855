/* Scene building: sc_scene -> ap_builder -> ap_model (include/appell/body.h).
 *
 * Elements are added in the order of the file, so builder ids equal scene indices (body i,
 * joint j, constraint c, effect e). A builder failure carries the builder's message and is
 * placed at the line of the element it names ("joint 'x'", "body 'x'", ...), or at the top of
 * the scene when it names none. Invariant: the builder is freed before returning; the model
 * does not refer to it. */
#include <stdio.h>
#include <string.h>

#include "scene/scene_int.h"

/* The scene node of the element a builder message names, or the root. */
static const sc_node *blame(const sc_scene *s, const char *msg) {
  static const char *const words[] = {"constraint '", "effect '", "joint '", "body '"};
  const char *best = NULL;
  const sc_node *node = s->root;
  for (int w = 0; w < 4; w++) {
    const char *p = strstr(msg, words[w]);
    if (!p || (best && p > best)) continue;
    const char *name = p + strlen(words[w]), *end = strchr(name, '\'');
    size_t len = end ? (size_t)(end - name) : 0;
    for (int i = 0; i < (w == 0 ? s->nc : w == 1 ? s->ne : w == 2 ? s->nj : s->nb); i++) {
      const char *nm = w == 0 ? s->cons[i].name : w == 1 ? s->effs[i].name
                     : w == 2 ? s->joints[i].name : s->bodies[i].name;
      const sc_node *nd = w == 0 ? s->cons[i].node : w == 1 ? s->effs[i].node
                        : w == 2 ? s->joints[i].node : s->bodies[i].node;
      if (strlen(nm) == len && strncmp(nm, name, len) == 0) best = p, node = nd;
    }
  }
  return node;
}

/* A builder call failed with rc: its message at node at (out of memory as such). */
static int builder_err(sc_ctx *c, const sc_node *at, ap_builder *b, int rc) {
  if (rc == AP_ERR_NOMEM) return sc_nomem(c);
  return sc_err(c, at, "%s", ap_builder_message(b));
}

static int add_bodies(sc_ctx *c, sc_scene *s, ap_builder *b) {
  for (int i = 0; i < s->nb; i++) {
    ap_body_def def = s->bodies[i].def;
    if (s->bodies[i].uniform && ap_body_def_uniform(&def, def.mass) != AP_OK)
      return sc_err(c, s->bodies[i].node, "cannot compute a uniform inertia for this shape");
    int rc = ap_builder_add_body(b, &def, NULL);
    if (rc != AP_OK) return builder_err(c, s->bodies[i].node, b, rc);
  }
  return AP_OK;
}

static int add_rest(sc_ctx *c, sc_scene *s, ap_builder *b) {
  int rc = AP_OK;
  for (int i = 0; i < s->nj; i++)
    if ((rc = ap_builder_add_joint(b, &s->joints[i].def, NULL)) != AP_OK)
      return builder_err(c, s->joints[i].node, b, rc);
  for (int i = 0; i < s->nc; i++)
    if ((rc = ap_builder_add_constraint(b, &s->cons[i].def, NULL)) != AP_OK)
      return builder_err(c, s->cons[i].node, b, rc);
  for (int i = 0; i < s->ne; i++)
    if ((rc = ap_builder_add_effect(b, &s->effs[i].def, NULL)) != AP_OK)
      return builder_err(c, s->effs[i].node, b, rc);
  return AP_OK;
}

/* The output asks for the load of a wheel contact (a rolling body not on a plane-contact
 * joint), which the dense path alone reports (docs/large.md, "Fleets"). */
static int wheel_loads_asked(const sc_scene *s) {
  if (!(s->channels & SC_OUT_CONTACT_FORCES)) return 0;
  for (int i = 0; i < s->nc; i++) {
    int plane = 0;
    for (int j = 0; j < s->nj && s->cons[i].def.kind == AP_CON_ROLLING; j++)
      plane |= s->joints[j].def.child == s->cons[i].def.body &&
               s->joints[j].def.kind == AP_JOINT_PLANE_CONTACT;
    if (s->cons[i].def.kind == AP_CON_ROLLING && !plane) return 1;
  }
  return 0;
}

int sc_build(sc_ctx *c, sc_scene *s, ap_model **out) {
  ap_builder *b = NULL;
  *out = NULL;
  if (ap_builder_create(s->name, &b) != AP_OK) return sc_nomem(c);
  int rc = add_bodies(c, s, b);
  if (rc == AP_OK) rc = add_rest(c, s, b);
  /* auto: the DAE mode and the linearization need the dense path's g and A, wheel loads its
   * subtree wrenches */
  int path = s->path;
  if (path == AP_PATH_AUTO && (s->run.sim.mode == AP_MODE_DAE || sc_map_get(s->root,
                                                                           "linearize")))
    path = AP_PATH_DENSE;
  if (path == AP_PATH_AUTO && wheel_loads_asked(s)) path = AP_PATH_DENSE;
  if (rc == AP_OK && path == AP_PATH_TREE && wheel_loads_asked(s))
    rc = sc_err(c, sc_map_get(s->root, "output"), "output.channels: contact_forces of wheel "
                "contacts (their loads) are reported on the dense path only (path: dense or "
                "auto)");
  if (rc == AP_OK) rc = ap_builder_set_path(b, (ap_path)path);
  int crc = rc == AP_OK ? ap_builder_compile(b, out) : AP_OK;
  if (crc == AP_ERR_NOMEM) rc = sc_nomem(c);
  else if (crc != AP_OK) {
    const char *msg = ap_builder_message(b);
    rc = sc_err(c, blame(s, msg ? msg : ""), "%s", msg && msg[0] ? msg : "the model does not "
                "compile");
  }
  ap_builder_free(b);
  return rc;
}
