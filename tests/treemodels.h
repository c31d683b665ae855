/* Large body models for the tree path (tests and bench_scaling share them).
 *   trailers  a car (planar joint, knife edge on its rear axle) pulling N trailers, each hinged
 *             about the vertical to the body before it, with a knife edge on its axle:
 *             k = N + 3 speeds, b = N + 1 rows, one chain.
 *   disks     N independent thin disks (radius 0.5, mass 1), each on its own plane-contact
 *             joint with a rolling constraint, under gravity: k = 5 N, b = 2 N.
 *   fleet     N differential-drive robots on one floor: a chassis (planar joint, origin on the
 *             axle 0.1 m above the floor), two thin wheels (radius 0.1, track 0.5) on revolute
 *             joints with rolling wheel contacts, viscous damping on the wheels' axles; every
 *             robot whose index i has i % trailer_every == trailer_every - 1 (trailer_every > 0)
 *             pulls a trailer hinged 0.3 m behind the axle with a knife edge on its own axle.
 *             k = 5 N + trailers, b = 6 N + trailers; every robot is one tree.
 * The path argument goes to ap_builder_set_path. States are consistent: the given speeds are
 * kept, the others completed (ap_body_complete_speeds). Failures print and exit(1). */
#ifndef TESTS_TREEMODELS_H
#define TESTS_TREEMODELS_H

#include "appell/appell.h"

ap_model *tm_trailers(int N, ap_path path);
ap_model *tm_disks(int N, ap_path path);
/* q (n), v (k): trailers in a zig-zag, the car at 2 m/s turning at 0.3 rad/s. */
void tm_trailers_state(const ap_model *m, int N, double *q, double *v);
/* Disks tilted 50-70 degrees from the vertical, spinning and turning, on a 2 m grid. */
/* N thin disks (radius 0.3, mass 1) on free joints, each rolling: wheel contacts whose
 * contact rows' phi drifts (projected after each step). */
ap_model *tm_free_disks(int N, ap_path path);
ap_model *tm_fleet(int N, int trailer_every, ap_path path);
/* Robots on a 2 m grid, headings spread, wheel rates 6..12 rad/s (turning both ways). */
void tm_fleet_state(const ap_model *m, int N, int trailer_every, double *q, double *v);
void tm_disks_state(const ap_model *m, int N, double *q, double *v);

#endif
