/* URDF import, internal: the robot as read from the XML (lib/scene/urdf.c) and handed to the
 * scene writer (lib/scene/urdf_emit.c). Poses are (position, unit quaternion [w x y z]) as in
 * URDF's <origin xyz rpy>, with R = Rz(yaw) Ry(pitch) Rx(roll). */
#ifndef AP_SCENE_URDF_INT_H
#define AP_SCENE_URDF_INT_H

#include <stddef.h>

#include <libxml/tree.h>

#include "appell/urdf.h"

typedef struct ur_pose {
  double p[3];
  double q[4];                 /* [w x y z] */
} ur_pose;

enum { UR_SHAPE_NONE = 0, UR_SHAPE_SPHERE = 1, UR_SHAPE_CYLINDER = 2 };

typedef struct ur_link {
  char name[128];              /* the scene's name (URDF name with other characters as '_') */
  char urdf_name[128];
  int line;
  int has_inertial;
  double mass;                 /* kg */
  ur_pose inertial;            /* inertial frame in link axes */
  double I[6];                 /* ixx ixy ixz iyy iyz izz in the inertial frame (kg m^2) */
  int shape;                   /* the first collision sphere or cylinder */
  double radius, length;       /* m */
  ur_pose shape_pose;          /* collision origin in link axes */
  int shape_line;
  int parent_joint;            /* index of the joint whose child it is, or -1 */
  int wheel;                   /* named in ap_urdf_def.wheels */
  int world;                   /* the link named "world": the ground */
} ur_link;

enum { UR_REVOLUTE, UR_CONTINUOUS, UR_PRISMATIC, UR_FIXED, UR_FLOATING, UR_PLANAR };

typedef struct ur_joint {
  char name[128];
  char urdf_name[128];
  int line;
  int type;
  int parent, child;           /* link indices */
  ur_pose origin;              /* joint frame in the parent link's axes */
  double axis[3];              /* unit, in the joint frame */
  int has_limit;
  double lower, upper;         /* rad or m */
  double damping;              /* N m s/rad or N s/m; 0 when absent */
} ur_joint;

typedef struct ur_robot {
  char name[128];
  ur_link *links;
  int nlinks;
  ur_joint *joints;
  int njoints;
  int root;                    /* the link without a parent joint */
  int *by_name;                /* link indices sorted by urdf_name (ur_index_links) */
} ur_robot;

/* Reading context: the file name and the one message (the first error wins). */
typedef struct ur_ctx {
  const char *file;
  char *msg;
  size_t msg_len;
  int status;
} ur_ctx;

/* "FILE:LINE: <element name='NAME'>: what"; returns AP_ERR_ARG (urdf.c). */
int ur_err(ur_ctx *c, const xmlNode *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Names and the tree (urdf_tree.c), each O(n log n) or O(n) in the number of links. Sort the
 * links by name and refuse duplicate names (URDF's, and the scene's once other characters
 * are '_'); find a link by its URDF name (-1 when none); refuse duplicate joint names; find
 * the root and refuse a cycle or a second root. */
int ur_index_links(ur_ctx *c, ur_robot *r, xmlNode *const *lnodes);
int ur_find_link(const ur_robot *r, const char *urdf_name);
int ur_check_joint_names(ur_ctx *c, const ur_robot *r, xmlNode *const *jnodes);
int ur_check_tree(ur_ctx *c, ur_robot *r, xmlNode *const *jnodes, xmlNode *const *lnodes);

/* Pose algebra (urdf_emit.c). */
void ur_quat_mul(const double a[4], const double b[4], double out[4]);
void ur_pose_rpy(const double rpy[3], double q[4]);

/* The scene text of a checked robot; AP_ERR_NOMEM or AP_ERR_ARG (msg) on failure. */
int ur_emit(const ur_robot *r, const ap_urdf_def *def, const char *file, char **yaml,
            size_t *len, char *msg, size_t msg_len);

#endif
