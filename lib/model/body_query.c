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
