/* Large body models for the tree path (tests and bench_scaling share them).
 *   trailers  a car (planar joint, knife edge on its rear axle) pulling N trailers, each hinged
 *             about the vertical to the body before it, with a knife edge on its axle:
 *             k = N + 3 speeds, b = N + 1 rows, one chain.
 *   disks     N independent thin disks (radius 0.5, mass 1), each on its own plane-contact
 *             joint with a rolling constraint, under gravity: k = 5 N, b = 2 N.
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
void tm_disks_state(const ap_model *m, int N, double *q, double *v);

#endif
