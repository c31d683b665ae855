/* Large body models for the tree path (treemodels.h). */
#include "treemodels.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void die(const char *what, const char *msg) {
  fprintf(stderr, "treemodels: %s: %s\n", what, msg);
  exit(1);
}

static void check(int rc, const char *what) {
  if (rc != AP_OK) die(what, ap_strerror(rc));
}

static void *xcalloc(size_t n, size_t size) {
  void *p = calloc(n ? n : 1, size);
  if (!p) die("memory", "out of memory");
  return p;
}

static ap_model *compile(ap_builder *b, ap_path path) {
  ap_model *m = NULL;
  check(ap_builder_set_path(b, path), "path");
  if (ap_builder_compile(b, &m) != AP_OK) die("compile", ap_builder_message(b));
  ap_builder_free(b);
  return m;
}

static int add_box(ap_builder *b, const char *name, double mass, double cx, double Izz) {
  ap_body_def d = ap_body_def_default();
  int id = -1;
  d.name = name, d.mass = mass, d.com[0] = cx;
  d.inertia[0] = 0.5 * Izz, d.inertia[4] = 0.6 * Izz, d.inertia[8] = Izz;
  check(ap_builder_add_body(b, &d, &id), name);
  return id;
}

static void knife(ap_builder *b, const char *name, int body) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = name, c.kind = AP_CON_KNIFE_EDGE, c.body = body;   /* origin, body y blocked */
  check(ap_builder_add_constraint(b, &c, NULL), name);
}

/* Trailer i + 1 (box: mass, com x, Izz) hinged about the vertical at x = hitch on body prev,
 * its own origin (the axle, with a knife edge) `behind` m behind the hinge; returns its id. */
static int trailer(ap_builder *b, int i, int prev, const double *box, double hitch,
                   double behind) {
  char name[64];
  snprintf(name, sizeof name, "trailer%d", i + 1);
  int id = add_box(b, name, box[0], box[1], box[2]);
  ap_joint_def j = ap_joint_def_default();
  j.name = name, j.kind = AP_JOINT_REVOLUTE, j.parent = prev, j.child = id;
  j.parent_frame.pos[0] = hitch, j.child_frame.pos[0] = behind;   /* axis: z (default) */
  check(ap_builder_add_joint(b, &j, NULL), name);
  snprintf(name, sizeof name, "trailer%d.axle", i + 1);
  knife(b, name, id);
  return id;
}

/* Car: origin at the rear axle, centre of mass 1 m ahead. Trailer i: origin at its axle, hitch
 * 1.2 m ahead of it, hinged 0.5 m behind the previous body's axle. */
ap_model *tm_trailers(int N, ap_path path) {
  ap_builder *b = NULL;
  check(ap_builder_create("trailers", &b), "builder");
  int prev = add_box(b, "car", 1000.0, 1.0, 1500.0);
  ap_joint_def j = ap_joint_def_default();
  j.name = "car", j.kind = AP_JOINT_PLANAR, j.child = prev;
  check(ap_builder_add_joint(b, &j, NULL), "car joint");
  knife(b, "car.axle", prev);
  for (int i = 0; i < N; i++) {
    const double box[3] = {300.0, 0.4, 250.0};
    prev = trailer(b, i, prev, box, -0.5, 1.2);
  }
  return compile(b, path);
}

/* N disks of radius r on joints of one kind, each with a rolling constraint, and gravity. */
static ap_model *disks(const char *model, int N, ap_joint_kind kind, double r, ap_path path) {
  ap_builder *b = NULL;
  char name[64];
  check(ap_builder_create(model, &b), "builder");
  for (int i = 0; i < N; i++) {
    snprintf(name, sizeof name, "disk%d", i + 1);
    ap_body_def d = ap_body_def_default();
    d.name = name, d.shape.kind = AP_SHAPE_DISK, d.shape.radius = r;
    check(ap_body_def_uniform(&d, 1.0), name);
    int id = -1;
    check(ap_builder_add_body(b, &d, &id), name);
    ap_joint_def j = ap_joint_def_default();
    j.name = name, j.kind = kind, j.child = id;
    check(ap_builder_add_joint(b, &j, NULL), name);
    ap_constraint_def c = ap_constraint_def_default();
    snprintf(name, sizeof name, "roll%d", i + 1);
    c.name = name, c.kind = AP_CON_ROLLING, c.body = id;
    check(ap_builder_add_constraint(b, &c, NULL), name);
  }
  ap_effect_def e = ap_effect_def_default();   /* gravity on every body */
  check(ap_builder_add_effect(b, &e, NULL), "gravity");
  return compile(b, path);
}

ap_model *tm_disks(int N, ap_path path) {
  return disks("disks", N, AP_JOINT_PLANE_CONTACT, 0.5, path);
}

ap_model *tm_free_disks(int N, ap_path path) {
  return disks("free_disks", N, AP_JOINT_FREE, 0.3, path);
}

static void complete(const ap_model *m, double *q, const int *given, double *v) {
  ap_data *d = NULL;
  check(ap_data_create(m, &d), "data");
  d->t = 0;
  if (ap_body_complete_speeds(m, d, q, given, v) != AP_OK) die("initial speeds", d->msg);
  ap_data_free(d);
}

void tm_trailers_state(const ap_model *m, int N, double *q, double *v) {
  int n = ap_model_n(m), k = ap_model_k(m);
  int *given = xcalloc((size_t)k, sizeof *given);
  memset(q, 0, sizeof(double) * (size_t)n);
  memset(v, 0, sizeof(double) * (size_t)k);
  for (int i = 0; i < N; i++) q[3 + i] = 0.15 * ((i % 2) ? -1.0 : 1.0);   /* zig-zag */
  v[0] = 2.0, v[2] = 0.3;     /* car: 2 m/s forward, turning at 0.3 rad/s */
  given[0] = given[2] = 1;
  complete(m, q, given, v);
  free(given);
}

void tm_disks_state(const ap_model *m, int N, double *q, double *v) {
  int k = ap_model_k(m);
  int *given = xcalloc((size_t)k, sizeof *given);
  const double ex[3] = {1, 0, 0};
  for (int i = 0; i < N; i++) {
    double *qi = q + 6 * i, *vi = v + 5 * i;
    double tilt = (50.0 + 20.0 * i / N) * 3.14159265358979323846 / 180.0;
    double R[9], spin = -6.0 + 0.5 * (i % 3), turn = 4.0;
    qi[0] = 2.0 * (i % 32), qi[1] = 2.0 * (i / 32);
    ap_quat_from_axis_angle(ex, tilt, qi + 2);   /* disk axis tilted from the vertical */
    ap_quat_to_matrix(qi + 2, R);
    vi[0] = vi[1] = 0;
    for (int r = 0; r < 3; r++) vi[2 + r] = spin * R[6 + r] + (r == 2 ? turn : 0.0);
    given[5 * i + 2] = given[5 * i + 3] = given[5 * i + 4] = 1;
  }
  complete(m, q, given, v);
  free(given);
}

static int fleet_trailer(int i, int every) { return every > 0 && i % every == every - 1; }

static void fleet_wheel(ap_builder *b, int i, int chassis, double y, const char *side) {
  char name[64];
  snprintf(name, sizeof name, "wheel_%s%d", side, i + 1);
  ap_body_def d = ap_body_def_default();
  d.name = name, d.shape.kind = AP_SHAPE_DISK, d.shape.radius = 0.1;
  check(ap_body_def_uniform(&d, 0.5), name);
  int id = -1;
  check(ap_builder_add_body(b, &d, &id), name);
  ap_joint_def j = ap_joint_def_default();   /* axis (joint z) along the chassis y axis */
  j.name = name, j.kind = AP_JOINT_REVOLUTE, j.parent = chassis, j.child = id;
  j.parent_frame.pos[1] = y;
  j.parent_frame.quat[0] = sqrt(0.5), j.parent_frame.quat[1] = -sqrt(0.5);
  int jid = -1;
  check(ap_builder_add_joint(b, &j, &jid), name);
  ap_effect_def e = ap_effect_def_default();
  e.kind = AP_EFFECT_JOINT_DAMPING, e.joint = jid, e.damping = 0.02 * (1 + i % 3);
  check(ap_builder_add_effect(b, &e, NULL), name);
  ap_constraint_def c = ap_constraint_def_default();
  snprintf(name, sizeof name, "roll_%s%d", side, i + 1);
  c.name = name, c.kind = AP_CON_ROLLING, c.body = id;
  check(ap_builder_add_constraint(b, &c, NULL), name);
}

ap_model *tm_fleet(int N, int trailer_every, ap_path path) {
  ap_builder *b = NULL;
  char name[64];
  check(ap_builder_create("fleet", &b), "builder");
  for (int i = 0; i < N; i++) {
    snprintf(name, sizeof name, "chassis%d", i + 1);
    int ch = add_box(b, name, 10.0 + i % 4, 0.1, 0.6);
    ap_joint_def j = ap_joint_def_default();
    j.name = name, j.kind = AP_JOINT_PLANAR, j.child = ch, j.parent_frame.pos[2] = 0.1;
    check(ap_builder_add_joint(b, &j, NULL), name);
    fleet_wheel(b, i, ch, 0.25, "l");
    fleet_wheel(b, i, ch, -0.25, "r");
    const double box[3] = {4.0, 0.2, 0.3};
    if (fleet_trailer(i, trailer_every)) trailer(b, i, ch, box, -0.3, 0.5);
  }
  ap_effect_def e = ap_effect_def_default();   /* gravity on every body */
  check(ap_builder_add_effect(b, &e, NULL), "gravity");
  return compile(b, path);
}

/* Index of the speed (or coordinate) named "<name><i>.<what>", or exit. */
static int fleet_index(const ap_model *m, int speed, const char *name, int i, const char *what) {
  char full[96];
  snprintf(full, sizeof full, "%s%d.%s", name, i + 1, what);
  int n = speed ? ap_model_k(m) : ap_model_n(m);
  for (int c = 0; c < n; c++)
    if (strcmp(speed ? ap_model_speed_name(m, c) : ap_model_coord_name(m, c), full) == 0) return c;
  die("fleet index", full);
  return -1;
}

void tm_fleet_state(const ap_model *m, int N, int trailer_every, double *q, double *v) {
  int n = ap_model_n(m), k = ap_model_k(m);
  int *given = xcalloc((size_t)k, sizeof *given);
  memset(q, 0, sizeof(double) * (size_t)n);
  memset(v, 0, sizeof(double) * (size_t)k);
  for (int i = 0; i < N; i++) {   /* chassis x, y, heading; wheel rates; trailer angle */
    q[fleet_index(m, 0, "chassis", i, "x")] = 2.0 * (i % 32);
    q[fleet_index(m, 0, "chassis", i, "y")] = 2.0 * (i / 32);
    q[fleet_index(m, 0, "chassis", i, "heading")] = 0.7 * i;
    int wl = fleet_index(m, 1, "wheel_l", i, "angle_dot");
    int wr = fleet_index(m, 1, "wheel_r", i, "angle_dot");
    v[wl] = 6.0 + 0.5 * (i % 7), v[wr] = 12.0 - 0.75 * (i % 5);
    given[wl] = given[wr] = 1;
    if (fleet_trailer(i, trailer_every))
      q[fleet_index(m, 0, "trailer", i, "angle")] = 0.2 * ((i % 2) ? -1.0 : 1.0);
  }
  complete(m, q, given, v);
  free(given);
}
