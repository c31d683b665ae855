/* The joint layout of a body model (model/layout.h): a copy of each compiled joint's index
 * tables, in topological order, for the analysis layer. */
#include "model/layout.h"

#include <math.h>
#include <string.h>

#include "model/model.h"

int ap_bm_joint_count(const ap_model *m) {
  return ap_model_is_body_model(m) ? ap_bm(m)->nj : 0;
}

static int z_symmetric(const ap_mbody *B) {
  const double *I = B->I;   /* column-major 3 x 3 */
  double tol = 1e-12 * (fabs(I[0]) + fabs(I[4]) + fabs(I[8]));
  if (fabs(I[0] - I[4]) > tol || fabs(I[3]) > tol || fabs(I[6]) > tol || fabs(I[7]) > tol)
    return 0;
  if (B->com[0] != 0.0 || B->com[1] != 0.0) return 0;
  switch (B->shape.kind) {
    case AP_SHAPE_ELLIPSOID: return B->shape.semi_axes[0] == B->shape.semi_axes[1];
    default: return 1;   /* none, point, sphere, disk, torus */
  }
}

int ap_bm_joint_layout(const ap_model *m, int j, ap_jlayout *out) {
  if (!ap_model_is_body_model(m) || !out || j < 0 || j >= ap_bm(m)->nj) return AP_ERR_ARG;
  const ap_mjoint *J = &ap_bm(m)->joints[j];
  memset(out, 0, sizeof *out);
  out->name = ap_bm(m)->bodies[J->child].name;
  out->kind = J->kind;
  out->parent = J->parent;
  out->nq = J->nq, out->nv = J->nv;
  memcpy(out->qidx, J->qidx, sizeof out->qidx);
  memcpy(out->vidx, J->vidx, sizeof out->vidx);
  out->quat = J->quat, out->wofs = J->wofs, out->ndrivable = J->ndrivable;
  out->zsym = z_symmetric(&ap_bm(m)->bodies[J->child]);
  return AP_OK;
}
