/* The joint layout of a compiled body model, for the analysis layer (lib/analyze): which
 * entries of q and v each joint owns, so that a chart of the configuration can be built
 * joint by joint without reading the body model's internals. */
#ifndef AP_MODEL_LAYOUT_H
#define AP_MODEL_LAYOUT_H

#include "appell/body.h"

typedef struct ap_jlayout {
  const char *name;        /* the child body's name, which prefixes the joint's coordinate and
                              speed names (owned by the model) */
  ap_joint_kind kind;
  int parent;              /* body id or AP_GROUND */
  int nq, nv;              /* local coordinates and speeds */
  int qidx[7], vidx[6];    /* global index of each local coordinate / speed; -1 = driven */
  int quat;                /* local index of the quaternion's w, or -1 */
  int wofs;                /* local index of the quaternion's first angular speed */
  int ndrivable;           /* local scalar coordinates 0..ndrivable-1 have speed i as rate */
  int zsym;                /* the child body is symmetric about its z axis: inertia with
                              I_xx = I_yy and no products with z, centre of mass on the axis,
                              shape none, point, sphere, disk, torus or an ellipsoid with equal
                              x and y semi-axes */
} ap_jlayout;

/* Number of joints of a body model (0 for a math-level model). */
int ap_bm_joint_count(const ap_model *m);
/* Layout of joint j in the model's (topological) order. AP_ERR_ARG for a bad index. */
int ap_bm_joint_layout(const ap_model *m, int j, ap_jlayout *out);

#endif
