/* Reusable parts and include (lib/scene/parts.c, include.c; docs/scenes.md "Parts and
 * include"), and Kron's way of joining known systems (examples/scenes/kron_two_pendulums.yaml).
 *
 *  - Errors, each with FILE:LINE:COLUMN: inside an included file (its own name), in a part
 *    (the part's file and line, and the instance), include cycles (the chain) and depth, a
 *    missing file, unknown parts, parameters and placeholders, a missing required value, a
 *    name defined twice. The files are written to a fresh temporary folder.
 *  - Places: entries written without a value keep the order of the elements for the copies;
 *    --set reaches the elements the copies define.
 *  - Kron: two copies of Hoffmann's two-rod pendulum (one part, instantiated twice) hung from
 *    O = (-d/2, 0) and D = (d/2, 0) in the y-z plane, their lower ends joined at B by a loop
 *    closure: a five-bar linkage with 2 degrees of freedom. The independent model here uses
 *    the upper rods' angles (t1, t2) as its two coordinates: A1 = O + L (sin t1, -cos t1),
 *    A2 = D + L (sin t2, -cos t2), B the lower intersection of the circles of radius L about
 *    A1 and A2; its Jacobians come from the complex step (exact to round-off), giving the mass
 *    matrix M(t) = sum m Jc^T Jc + I Jw^T Jw over the four rods and V = sum m g z_c.
 *    (1) Along the scene's motion (10 s, rtol 1e-10) the model's energy T + V, evaluated from
 *    (t1, t2, t1', t2') alone, equals the scene's own energy to round-off at every output
 *    (both are the same function of the state when the scene's closure holds) and stays
 *    constant: bound 1e-8 of the energy scale (the integrator's tolerance over 10 s).
 *    (2) The equilibrium (Newton on grad V) and the small-oscillation frequencies from
 *    det(K - w^2 M) = 0 (K the Hessian of V by central differences of the complex-step
 *    gradient, error ~1e-10) against the linearizer's operating point and eigenvalues of the
 *    scene: within 1e-9 relative.
 *  - Running out of memory: loading the Kron scene (an include, two instances, parameters)
 *    with each of its allocations failing in turn gives AP_ERR_NOMEM or a message saying
 *    memory ran out, and leaks nothing (tests/alloc.h counts the live blocks). */
#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <appell/appell.h>

#include "alloc.h"
#include "check.h"
#include "clitest.h"
#include "scene/scene_int.h"

static char srcdir[1024], tmp[256];

static void write_file(const char *name, const char *text) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", tmp, name);
  FILE *f = fopen(path, "w");
  AP_CHECK(f != NULL);
  if (!f) return;
  fputs(text, f);
  fclose(f);
}

/* Load tmp/name with one override (or none): the status and message. */
static int load(const char *name, const char *set, char *msg, size_t len) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", tmp, name);
  ap_scene *sc = NULL;
  const char *sets[] = {set};
  int rc = ap_scene_load(path, sets, set ? 1 : 0, &sc, msg, len);
  ap_scene_free(sc);
  return rc;
}

static const char wheel[] =
    "parts:\n"
    "  wheel:\n"
    "    parameters: {parent: ground, r: 0.15, y: 0, need: }\n"
    "    bodies:\n"
    "      ${prefix}disk: {mass: $need, shape: {kind: disk, radius: $r}, inertia: uniform}\n"
    "    joints:\n"
    "      ${prefix}disk: {kind: revolute, parent: $parent, parent_frame: {pos: [0, $y, 1]}}\n";

static void expect(const char *name, const char *set, const char *where, const char *what) {
  char msg[1024] = "";
  int rc = load(name, set, msg, sizeof msg);
  int ok = rc == AP_ERR_ARG && strstr(msg, where) && strstr(msg, what);
  if (!ok) fprintf(stderr, "  %s: rc %d, message: %s\n  (wanted '%s' ... '%s')\n", name, rc, msg,
                   where, what);
  else printf("  %s\n", msg + (strncmp(msg, tmp, strlen(tmp)) ? 0 : strlen(tmp) + 1));
  AP_CHECK(ok);
}

static void test_errors(void) {
  write_file("wheel.yaml", wheel);
  write_file("cyc_a.yaml", "include: cyc_b.yaml\nbodies: {}\n");
  write_file("cyc_b.yaml", "include: [cyc_a.yaml]\n");
  expect("cyc_a.yaml", NULL, "cyc_b.yaml:1:11: include[0]", "include each other in a cycle");
  expect("cyc_a.yaml", NULL, "cyc_b.yaml", "cyc_a.yaml -> ");
  for (int i = 0; i < 10; i++) {
    char name[32], text[64];
    snprintf(name, sizeof name, "deep%d.yaml", i);
    snprintf(text, sizeof text, "include: deep%d.yaml\n", i + 1);
    write_file(name, text);
  }
  expect("deep0.yaml", NULL, "deep7.yaml:1:10: include", "nest deeper than 8 files");
  write_file("missing.yaml", "include: nowhere.yaml\n");
  expect("missing.yaml", NULL, "missing.yaml:1:10: include", "cannot include");
  write_file("bad_inc.yaml", "bodies:\n  disk: {mass: -1}\n");
  write_file("uses_bad.yaml", "include: bad_inc.yaml\njoints: {disk: {kind: revolute}}\n");
  expect("uses_bad.yaml", NULL, "bad_inc.yaml:2:16: bodies.disk.mass", "must be positive");
  write_file("broken.yaml", "bodies: [\n");
  write_file("uses_broken.yaml", "include: broken.yaml\n");
  expect("uses_broken.yaml", NULL, "broken.yaml:", "(included at ");
  static const char inst[] = "include: wheel.yaml\ninstances:\n  left: {part: wheel, "
                             "parameters: {need: 1, r: %s}}\n  right: {part: %s, parameters: "
                             "{need: 1, %s: 0.2}}\n";
  char text[512];
  snprintf(text, sizeof text, inst, "-0.1", "wheel", "y");
  write_file("neg.yaml", text);
  expect("neg.yaml", NULL, "wheel.yaml:5:64: bodies.left_disk.shape.radius (in part 'wheel' as "
         "'left', ", "neg.yaml:3:3): must be positive");
  snprintf(text, sizeof text, inst, "0.1", "whel", "y");
  write_file("nopart.yaml", text);
  expect("nopart.yaml", NULL, "nopart.yaml:4:17: instances.right.part",
         "no part named 'whel' (did you mean 'wheel'?)");
  snprintf(text, sizeof text, inst, "0.1", "wheel", "yy");
  write_file("noparam.yaml", text);
  expect("noparam.yaml", NULL, "noparam.yaml:4:46: instances.right.parameters.yy",
         "part 'wheel' has no parameter 'yy' (did you mean 'y'?)");
  expect("noparam.yaml", "instances.right.parameters.yy=0", "instances.right.parameters.yy",
         "no parameter 'yy'");
  write_file("noneed.yaml", "include: wheel.yaml\ninstances:\n  left: {part: wheel}\n");
  expect("noneed.yaml", NULL, "wheel.yaml:3:55: parts.wheel.parameters.need",
         "part 'wheel' needs a value of 'need' from instance 'left'");
  write_file("twice.yaml", "include: wheel.yaml\ninstances:\n  a: {part: wheel, prefix: x, "
             "parameters: {need: 1}}\n  b: {part: wheel, prefix: x, parameters: {need: 1}}\n");
  expect("twice.yaml", NULL, "wheel.yaml:5:7: bodies.xdisk (in part 'wheel' as 'b'",
         "'xdisk' is defined twice: here and at ");
  write_file("holder.yaml", "parts:\n  p:\n    bodies: {$what: {mass: 1}}\n"
             "instances: {a: {part: p}}\njoints: {}\n");
  expect("holder.yaml", NULL, "holder.yaml:3:14: bodies", "unknown placeholder '$what'");
}

/* Two instances and an override of one instance's parameter. */
static void test_good(void) {
  write_file("two.yaml", "include: wheel.yaml\nparameters: {track: 0.8}\ninstances:\n"
             "  l: {part: wheel, parameters: {need: 1, y: track/2}}\n"
             "  r: {part: wheel, parameters: {need: 1, y: -track/2}}\n");
  char path[512], msg[1024];
  snprintf(path, sizeof path, "%s/two.yaml", tmp);
  const char *sets[] = {"instances.r.parameters.r=0.25"};
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, sets, 1, &sc, msg, sizeof msg);
  if (rc) fprintf(stderr, "%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (!sc) return;
  AP_CHECK_EQ_INT(ap_scene_count(sc, AP_SCENE_BODIES), 2);
  AP_CHECK(!strcmp(ap_scene_element_name(sc, AP_SCENE_BODIES, 0), "l_disk"));
  AP_CHECK(!strcmp(ap_scene_element_name(sc, AP_SCENE_BODIES, 1), "r_disk"));
  const sc_scene *s = sc_scene_parsed(sc);
  AP_CHECK(s->bodies[0].def.shape.radius == 0.15 && s->bodies[1].def.shape.radius == 0.25);
  AP_CHECK(s->joints[0].def.parent_frame.pos[1] == 0.4);
  AP_CHECK(s->joints[1].def.parent_frame.pos[1] == -0.4);
  ap_scene_free(sc);
}

/* An entry written without a value keeps its place for the instance that defines it: the
 * elements are built in the file's order (hub, l_disk, arm, r_disk), not with the copies last;
 * an unfilled place is refused. A --set of an element an instance defines applies after the
 * copy (it is the copy's value that changes); one of instances: before it. */
static void test_places(void) {
  write_file("places.yaml", "include: wheel.yaml\nbodies:\n  hub: {mass: 2, inertia: [1, 1, 1]}\n"
             "  l_disk:\n  arm: {mass: 3, inertia: [1, 1, 1]}\n  r_disk: ~\n"
             "joints:\n  hub: {kind: revolute}\n  l_disk:\n  arm: {kind: revolute}\n"
             "instances:\n  l: {part: wheel, parameters: {need: 1, parent: hub}}\n"
             "  r: {part: wheel, parameters: {need: 1, parent: arm}}\n");
  char path[512], msg[1024];
  snprintf(path, sizeof path, "%s/places.yaml", tmp);
  const char *sets[] = {"bodies.r_disk.mass=5", "joints.l_disk.parent_frame.pos.1=0.5",
                        "instances.r.parameters.r=0.25"};
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, sets, 3, &sc, msg, sizeof msg);
  if (rc) fprintf(stderr, "%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (!sc) return;
  static const char *const order[] = {"hub", "l_disk", "arm", "r_disk"};
  AP_CHECK_EQ_INT(ap_scene_count(sc, AP_SCENE_BODIES), 4);
  AP_CHECK_EQ_INT(ap_scene_count(sc, AP_SCENE_JOINTS), 4);
  for (int i = 0; i < 4; i++) {
    AP_CHECK(!strcmp(ap_scene_element_name(sc, AP_SCENE_BODIES, i), order[i]));
    AP_CHECK(!strcmp(ap_scene_element_name(sc, AP_SCENE_JOINTS, i), i == 3 ? "r_disk" : order[i]));
  }
  const sc_scene *s = sc_scene_parsed(sc);
  AP_CHECK(s->bodies[1].def.mass == 1 && s->bodies[3].def.mass == 5);
  AP_CHECK(s->bodies[3].def.shape.radius == 0.25);
  AP_CHECK(s->joints[1].def.parent_frame.pos[1] == 0.5);
  AP_CHECK(s->joints[3].def.parent_frame.pos[1] == 0);
  ap_scene_free(sc);
  write_file("unfilled.yaml", "include: wheel.yaml\n"
             "bodies:\n  hub: {mass: 2, inertia: [1, 1, 1]}\n  x_disk:\n"
             "joints: {hub: {kind: revolute}}\n"
             "instances:\n  l: {part: wheel, parameters: {need: 1, parent: hub}}\n");
  expect("unfilled.yaml", NULL, "unfilled.yaml:4:10: bodies.x_disk", "expected a mapping");
  expect("places.yaml", "bodies.m_disk.mass=5", "--set bodies.m_disk.mass=5",
         "bodies has no body 'm_disk'");
}

/* ---- Kron: the closed chain against its two-coordinate model ---------------------------- */

enum { RODS = 4 };
static const double L = 1.0, d = 1.2, mass = 1.0, grav = 9.81;

/* Centres (y, z) of the four rods and the angles' carriers at coordinates t (complex for the
 * step): c[2 r], c[2 r + 1]; w[r] the direction vector (end - start) / L of rod r. */
static void chain(const double complex t[2], double complex c[2 * RODS],
                  double complex w[2 * RODS]) {
  double complex O[2] = {-d / 2, 0}, D[2] = {d / 2, 0};
  double complex A1[2] = {O[0] + L * csin(t[0]), O[1] - L * ccos(t[0])};
  double complex A2[2] = {D[0] + L * csin(t[1]), D[1] - L * ccos(t[1])};
  double complex e[2] = {A2[0] - A1[0], A2[1] - A1[1]};
  double complex h = csqrt(e[0] * e[0] + e[1] * e[1]), s = csqrt(L * L - h * h / 4);
  double complex B[2] = {(A1[0] + A2[0]) / 2 + s * e[1] / h, (A1[1] + A2[1]) / 2 - s * e[0] / h};
  const double complex *from[RODS] = {O, A1, A2, D}, *to[RODS] = {A1, B, B, A2};
  for (int r = 0; r < RODS; r++)
    for (int i = 0; i < 2; i++) {
      c[2 * r + i] = (from[r][i] + to[r][i]) / 2;
      w[2 * r + i] = (to[r][i] - from[r][i]) / L;
    }
}

/* M(t) (2 x 2, row-major) and V(t). The rod angle's rate is the cross product of its unit
 * direction with that direction's rate. */
static void model(const double t[2], double M[4], double *V) {
  double complex c[2 * RODS], w[2 * RODS], Jc[2][2 * RODS], Jw[2][2 * RODS];
  const double hs = 1e-30, Iz = mass * L * L / 12;
  for (int j = 0; j < 2; j++) {
    double complex tc[2] = {t[0], t[1]};
    tc[j] += hs * _Complex_I;
    chain(tc, Jc[j], Jw[j]);
    for (int i = 0; i < 2 * RODS; i++)
      Jc[j][i] = cimag(Jc[j][i]) / hs, Jw[j][i] = cimag(Jw[j][i]) / hs;
  }
  double complex t0[2] = {t[0], t[1]};
  chain(t0, c, w);
  *V = 0.0;
  memset(M, 0, 4 * sizeof *M);
  for (int r = 0; r < RODS; r++) {
    *V += mass * grav * creal(c[2 * r + 1]);
    double om[2];
    for (int j = 0; j < 2; j++)
      om[j] = creal(w[2 * r]) * creal(Jw[j][2 * r + 1]) -
              creal(w[2 * r + 1]) * creal(Jw[j][2 * r]);
    for (int a = 0; a < 2; a++)
      for (int b = 0; b < 2; b++)
        M[2 * a + b] += mass * (creal(Jc[a][2 * r]) * creal(Jc[b][2 * r]) +
                                creal(Jc[a][2 * r + 1]) * creal(Jc[b][2 * r + 1])) +
                        Iz * om[a] * om[b];
  }
}

/* dV/dt by the complex step. */
static void grad(const double t[2], double gV[2]) {
  const double hs = 1e-30;
  for (int j = 0; j < 2; j++) {
    double complex tc[2] = {t[0], t[1]}, c[2 * RODS], w[2 * RODS], V = 0;
    tc[j] += hs * _Complex_I;
    chain(tc, c, w);
    for (int r = 0; r < RODS; r++) V += mass * grav * c[2 * r + 1];
    gV[j] = cimag(V) / hs;
  }
}

/* The Hessian of V (row-major) by central differences of the exact gradient. */
static void hessian(const double t[2], double K[4]) {
  const double h = 1e-5;
  for (int j = 0; j < 2; j++) {
    double tp[2] = {t[0], t[1]}, tm[2] = {t[0], t[1]}, gp[2], gm[2];
    tp[j] += h, tm[j] -= h;
    grad(tp, gp);
    grad(tm, gm);
    for (int i = 0; i < 2; i++) K[2 * i + j] = (gp[i] - gm[i]) / (2 * h);
  }
}

static double energy(const double t[2], const double td[2]) {
  double M[4], V;
  model(t, M, &V);
  return 0.5 * (M[0] * td[0] * td[0] + 2 * M[1] * td[0] * td[1] + M[3] * td[1] * td[1]) + V;
}

static ap_scene *kron_scene(void) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/kron_two_pendulums.yaml", srcdir);
  ap_scene *sc = NULL;
  int rc = ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return sc;
}

static void test_kron_energy(void) {
  ap_scene *sc = kron_scene();
  if (!sc) return;
  const ap_model *m = ap_scene_model(sc);
  AP_CHECK_EQ_INT(ap_model_n(m), 4);
  AP_CHECK_EQ_INT(ap_model_b(m), 2);
  int i1 = ap_model_find_coord(m, "left_upper.angle"), i2 = ap_model_find_coord(m, "right_upper.angle");
  double q[8], v[8];
  char msg[1024];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, 0.0, q, v, &sim, msg, sizeof msg), AP_OK);
  double E0 = 0, Es0 = 0, drift = 0, offset = 0, scale = 0;
  for (int k = 0; sim && k <= 1000; k++) {
    if (k && ap_sim_advance(sim, 0.01 * k) != AP_OK) break;
    const double *x = ap_sim_q(sim), *xd = ap_sim_v(sim);
    double t[2] = {x[i1], x[i2]}, td[2] = {xd[i1], xd[i2]}, Es = 0, M[4], V;
    double E = energy(t, td);
    AP_CHECK_EQ_INT(ap_scene_energy(sc, 0.01 * k, x, xd, &Es), AP_OK);
    model(t, M, &V);
    if (k == 0) E0 = E, Es0 = Es, scale = fabs(V) + fabs(E - V);
    drift = fmax(drift, fabs(E - E0));
    offset = fmax(offset, fabs((E - E0) - (Es - Es0)));
  }
  printf("Kron's closed chain, 10 s: the two-coordinate model's energy drifts by %.3g (scale "
         "%.3g); it differs from the scene's energy by %.3g beyond their constant offset\n",
         drift, scale, offset);
  AP_CHECK_LE(drift, 1e-8 * scale);
  AP_CHECK_LE(offset, 1e-12 * scale);
  AP_CHECK(ap_sim_time(sim) == 10.0);
  ap_sim_free(sim);
  ap_scene_free(sc);
}

static void test_kron_modes(void) {
  double t[2] = {0.16, -0.16}, g[2], K[4], M[4], V;
  for (int it = 0; it < 30; it++) {   /* Newton on grad V */
    grad(t, g);
    hessian(t, K);
    double det = K[0] * K[3] - K[1] * K[2];
    t[0] -= (K[3] * g[0] - K[1] * g[1]) / det;
    t[1] -= (-K[2] * g[0] + K[0] * g[1]) / det;
  }
  grad(t, g);
  hessian(t, K);
  model(t, M, &V);
  double a = M[0] * M[3] - M[1] * M[2], b = K[0] * M[3] + K[3] * M[0] - K[1] * M[2] - K[2] * M[1],
         c = K[0] * K[3] - K[1] * K[2], disc = sqrt(b * b - 4 * a * c);
  double w[2] = {sqrt((b - disc) / (2 * a)), sqrt((b + disc) / (2 * a))};
  printf("independent model: equilibrium t1 %.15g t2 %.15g (|grad V| %.2g), frequencies %.15g "
         "%.15g rad/s\n", t[0], t[1], hypot(g[0], g[1]), w[0], w[1]);
  ap_scene *sc = kron_scene();
  if (!sc) return;
  const ap_model *m = ap_scene_model(sc);
  char msg[1024];
  double q[8], v[8];
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  static const char *const ind[] = {"left_upper.angle", "right_upper.angle",
                                    "left_upper.angle_dot", "right_upper.angle_dot", NULL};
  ap_lin_def def = ap_lin_def_default();
  def.about = AP_LIN_EQUILIBRIUM, def.independent = ind;
  int i1 = ap_model_find_coord(m, "left_upper.angle"), i2 = ap_model_find_coord(m, "right_upper.angle");
  int l1 = ap_model_find_coord(m, "left_lower.angle"), l2 = ap_model_find_coord(m, "right_lower.angle");
  q[i1] = 0.16, q[i2] = -0.16, q[l1] = 0.29, q[l2] = -0.29;   /* the section's guess */
  ap_lin *Ln = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, v, &Ln), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(Ln, NAN), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_linearize(Ln), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_eigen(Ln, NULL, 0, 1), AP_OK);
  ap_lin_eig e;
  AP_CHECK_EQ_INT(ap_lin_get_eigen(Ln, &e), AP_OK);
  AP_CHECK_EQ_INT(e.n, 4);
  double found[2] = {HUGE_VAL, 0};
  for (int i = 0; i < e.n; i++) {
    AP_CHECK_LE(fabs(e.re[i]), 1e-10);
    found[0] = fmin(found[0], fabs(e.im[i])), found[1] = fmax(found[1], fabs(e.im[i]));
  }
  printf("appell linearize: equilibrium t1 %.15g t2 %.15g, frequencies %.15g %.15g rad/s\n",
         ap_lin_q(Ln)[i1], ap_lin_q(Ln)[i2], found[0], found[1]);
  AP_CHECK_NEAR(ap_lin_q(Ln)[i1], t[0], 1e-9);
  AP_CHECK_NEAR(ap_lin_q(Ln)[i2], t[1], 1e-9);
  AP_CHECK_NEAR(found[0], w[0], 1e-9 * w[0]);
  AP_CHECK_NEAR(found[1], w[1], 1e-9 * w[1]);
  ap_lin_free(Ln);
  ap_scene_free(sc);
}

/* Under AddressSanitizer its own strdup allocates without calling malloc (tests/alloc.h), so
 * the live count is off by those blocks; LeakSanitizer checks for leaks in that build. */
#if defined(__SANITIZE_ADDRESS__)
#define COUNTS_LIVE_BLOCKS 0
#else
#define COUNTS_LIVE_BLOCKS 1
#endif

static void test_nomem(void) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/kron_two_pendulums.yaml", srcdir);
  int tried = 0, failed = 0, bad = 0;
  for (long i = 0; i < 100000; i++) {
    ap_scene *sc = NULL;
    long live = n_live;
    ap_alloc_fail_at(i);
    int rc = ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg), hit = ap_alloc_failed;
    ap_alloc_fail_at(-1);
    ap_scene_free(sc);
    tried++;
    if (rc != AP_OK) failed++;
    if ((rc != AP_OK && rc != AP_ERR_NOMEM && !strstr(msg, "memory")) ||
        (COUNTS_LIVE_BLOCKS && n_live != live) ||
        (rc == AP_OK && !sc)) {
      if (bad++ < 5) fprintf(stderr, "  allocation %ld: rc %d, %ld blocks leaked: %s\n", i, rc,
                             n_live - live, msg);
    }
    if (!hit) break;   /* every allocation of the load has been made to fail */
  }
  printf("Kron scene load with each allocation failing in turn: %d loads, %d failed, %d wrong\n",
         tried, failed, bad);
  AP_CHECK(tried > 100);
  AP_CHECK_EQ_INT(bad, 0);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  test_nomem();
  snprintf(tmp, sizeof tmp, "/tmp/appell_parts_XXXXXX");
  AP_CHECK(mkdtemp(tmp) != NULL);
  test_errors();
  test_good();
  test_places();
  test_kron_energy();
  test_kron_modes();
  char cmd[400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  AP_CHECK_EQ_INT(system(cmd), 0);
  return ap_check_finish("test_parts");
}
