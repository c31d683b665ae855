/* Public queries on a compiled body model's bodies: the name and the shape of body `b` (ids in
 * the order of creation, as ap_model_find_body and ap_body_get_state use them). A viewer or an
 * exporter draws each body from these and from ap_body_get_state's pose. */
#include <string.h>

#include "model/model.h"

const char *ap_model_body_name(const ap_model *m, int b) {
  if (!ap_model_is_body_model(m) || b < 0 || b >= ap_bm(m)->nb) return NULL;
  return ap_bm(m)->bodies[b].name;
}

int ap_model_body_shape(const ap_model *m, int b, ap_shape *out) {
  if (!ap_model_is_body_model(m) || !out || b < 0 || b >= ap_bm(m)->nb) return AP_ERR_ARG;
  *out = ap_bm(m)->bodies[b].shape;
  return AP_OK;
}

/* The ground surface of a rolling or knife-edge constraint as compiled: a plane with its unit
 * normal (z = 0: (0, 0, 1)) and offset, or a sphere; the motion fields as defined. */
int ap_model_constraint_ground(const ap_model *m, int c, ap_ground_motion *out) {
  if (!ap_model_is_body_model(m) || !out || c < 0 || c >= ap_bm(m)->nc) return AP_ERR_ARG;
  const ap_mcon *mc = &ap_bm(m)->cons[c];
  if (mc->def.kind != AP_CON_ROLLING && mc->def.kind != AP_CON_KNIFE_EDGE)
    return AP_ERR_UNSUPPORTED;
  *out = mc->def.ground;
  double z[3] = {0, 0, 1};
  memcpy(out->normal, mc->plane == 1 ? mc->gn : z, sizeof z);
  out->offset = mc->plane == 1 ? mc->goff : 0;
  if (mc->plane == 2) {
    memcpy(out->sphere_center, mc->gc, sizeof mc->gc);
    out->sphere_radius = mc->grad, out->inside = mc->gside < 0;
  } else {
    out->sphere_radius = 0;
  }
  return AP_OK;
}
