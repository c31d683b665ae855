/* Appell: URDF import.
 *
 * ap_urdf_to_scene reads a robot description in URDF (the Unified Robot Description Format of
 * ROS: links with inertial and collision elements, joints between them) and writes the
 * equivalent scene (docs/scenes.md) as YAML text, which ap_scene_load_string loads. The
 * mapping is in docs/urdf.md: links become bodies (mass, centre of mass and inertia tensor
 * turned into the body axes), joints keep their kind, origin, axis and limits, collision
 * spheres become sphere shapes, the links named as wheels get a disk (or torus) of their
 * collision cylinder's radius and a rolling contact with the ground. Every message about bad
 * input has the form
 *
 *     FILE:LINE: <element name='...'>: what is wrong
 *
 * (FILE:LINE:COLUMN for XML syntax errors). */
#ifndef APPELL_URDF_H
#define APPELL_URDF_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ap_urdf_wheel_shape {
  AP_URDF_WHEEL_DISK = 0,  /* a thin disk of the cylinder's radius (default) */
  AP_URDF_WHEEL_TORUS = 1  /* a torus of outer radius the cylinder's radius and tube radius
                              half its length (the length must be below the radius) */
} ap_urdf_wheel_shape;

typedef struct ap_urdf_def {
  const char *const *wheels;      /* names of the links that roll on the ground; default NULL */
  int nwheels;                    /* how many; default 0 */
  ap_urdf_wheel_shape wheel_shape; /* default AP_URDF_WHEEL_DISK */
  int internal_check;             /* set by ap_urdf_def_default(), never by hand */
} ap_urdf_def;

AP_API ap_urdf_def ap_urdf_def_default(void);

/* Convert the URDF file at path to scene text: *yaml is a NUL-terminated string of *len
 * bytes, to be freed with ap_scene_text_free. def may be NULL (the defaults). On failure
 * *yaml is NULL, the status is AP_ERR_ARG for bad input (AP_ERR_NOMEM when out of memory)
 * and msg holds the one located message. */
AP_API int ap_urdf_to_scene(const char *path, const ap_urdf_def *def, char **yaml, size_t *len,
                            char *msg, size_t msg_len);

#ifdef __cplusplus
}
#endif
#endif
