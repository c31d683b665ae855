/* Tolerances follow the model's units (issue 24): a model scaled from metres to other units of
 * length, time or mass moves as the original, and redundant constraint rows are dropped or
 * refused alike in every unit. A tolerance compared in absolute terms against a quantity with
 * units (rank_rtol against the gradient of a contact row, a consistency residual against
 * max(1, ...) or against 1 m/s plus the terms, the largest entry of A times the largest speed,
 * which pairs a lever arm with a linear speed) would treat the scaled models differently.
 *
 * 1. Example scenes in millimetres (lengths x 1000, inertias x 1e6 with the masses unchanged,
 *    gravity x 1000, atol x 1000): the rolling disk (plane contact, rolling rows, gravity) and
 *    the sleigh on a wheel (a knife edge on a wheel on a revolute below a planar chassis: the
 *    wheel's contact row vanishes identically, and rows of Phi_q below rank_rtol times the
 *    model's length scale are left out). Minimal and projected mode, 3 s, outputs every 0.5 s.
 * 2. Redundant drives (tests/scenes/units_drives.yaml: a cart on a prismatic joint with a
 *    pendulum, its speed prescribed twice; units_turns.yaml: a skate with a knife edge 0.5 m
 *    ahead of its origin, its heading rate prescribed twice) in metres, millimetres,
 *    micrometres, kilometres, milliseconds and grams. The second drive's value is the first's
 *    times 1 + delta: delta = 1e-9 is consistent (its residual is 1e-9 of the rows' terms and
 *    floors, below AP_CONSISTENCY_RTOL 1e-8: the row is dropped) and every unit must give the
 *    metre run's motion (the cart also at rest with both drives 0: every term zero); delta =
 *    1e-6 (the value, or for the cart the slope of a value growing with t, so that only gamma
 *    disagrees at t = 0) is inconsistent (1.6e-8 of the cart's terms and floor, 2.2e-7 of the
 *    skate's) and every unit but milliseconds (see same_refusal) must refuse it, on the dense
 *    path and for the cart on the tree path. On the tolerances before commit 6f1fa64 (1e-8
 *    max(1, |a0|), max(1, |a0|, |A|), max(1, |gamma|)), and on those of 6f1fa64 (floors of
 *    1 model unit per second, max|A| max|v|), 7 of these checks fail: the metre, kilometre and
 *    gram carts run with the contradictory drives that the millimetre and micrometre carts
 *    refuse (dense and tree path), and the kilometre cart runs with the contradictory slopes.
 *    The skate (refused alike there too, at creation, where v is not yet set) starts from its
 *    state given here, so that ap_sim_create, not the scene's own check, judges its rows.
 * Bound, per compared value: the sum of the two runs' global errors, each 10 (rtol X + atol_m),
 * X the largest magnitude of that quantity along the metre run, atol_m the metre run's atol
 * (the scaled run's atol is atol_m times the smallest of its factors, so its error in metre
 * units is below that). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "clitest.h"

#define MAXSET 16
#define NOUT 7   /* t = 0, 0.5, ..., 3 */

typedef struct ucase {
  const char *file;
  const char *lengths[8];   /* coordinate and speed names in length units */
  const char *mm[MAXSET];   /* the overrides to millimetres */
} ucase;

static const ucase CASES[] = {
    {"rolling_disk.yaml",
     {"disk.x", "disk.y", "disk.vx", "disk.vy", NULL},
     {"bodies.disk.shape.radius=500", "effects.gravity.g.2=-9810", NULL}},
    {"sleigh_wheel.yaml",
     {"sleigh.x", "sleigh.y", "sleigh.x_dot", "sleigh.y_dot", NULL},
     {"bodies.sleigh.com.0=1000/0.9", "bodies.sleigh.inertia.0=0.5e6",
      "bodies.sleigh.inertia.1=0.5e6", "bodies.sleigh.inertia.2=(2 - 1/0.9 - 0.1*0.1^2/4)*1e6",
      "bodies.wheel.shape.radius=100", "joints.sleigh.parent_frame.pos.2=100",
      "initial.sleigh.vx=-100", NULL}},
};

static const double RTOL = 1e-9, ATOL_M = 1e-12;

/* Run the scene (with its overrides) in mode to 3 s; the state at each output into x. */
static int run(const ucase *c, int mm, const char *mode, double *x, int *nx, char *names[64]) {
  char path[1200], msg[1024] = "", modeset[64], rt[64], at[64];
  ct_source(path, sizeof path, "examples/scenes", c->file);
  const char *sets[MAXSET + 8];
  int ns = 0;
  snprintf(modeset, sizeof modeset, "simulation.mode=%s", mode);
  snprintf(rt, sizeof rt, "simulation.rtol=%g", RTOL);
  snprintf(at, sizeof at, "simulation.atol=%g", mm ? 1e3 * ATOL_M : ATOL_M);
  sets[ns++] = modeset, sets[ns++] = rt, sets[ns++] = at, sets[ns++] = "simulation.t_end=3";
  for (int i = 0; mm && c->mm[i]; i++) sets[ns++] = c->mm[i];
  ap_scene *s = NULL;
  int rc = ap_scene_load(path, sets, ns, &s, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) {
    fprintf(stderr, "%s: %s\n", c->file, msg);
    return rc;
  }
  const ap_model *m = ap_scene_model(s);
  int n = ap_model_n(m), k = ap_model_k(m);
  *nx = n + k;
  for (int i = 0; i < n + k && i < 64; i++)
    names[i] = (char *)(i < n ? ap_model_coord_name(m, i) : ap_model_speed_name(m, i - n));
  ap_scene_run sr;
  ap_scene_get_run(s, &sr);
  double *q0 = calloc((size_t)(n + k), sizeof(double)), *v0 = q0 + n;
  rc = ap_scene_initial_state(s, q0, v0, NULL, 0, msg, sizeof msg);
  ap_sim *sim = NULL;
  if (rc == AP_OK) rc = ap_sim_create(m, &sr.sim, 0.0, q0, v0, &sim, msg, sizeof msg);
  for (int o = 0; rc == AP_OK && o < NOUT; o++) {
    if (o > 0) rc = ap_sim_advance(sim, 0.5 * o);
    memcpy(x + (size_t)o * (n + k), ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(x + (size_t)o * (n + k) + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
  }
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) fprintf(stderr, "%s: %s %s\n", c->file, msg, sim ? ap_sim_message(sim) : "");
  ap_sim_free(sim);
  free(q0);
  /* names point into the model: keep the scene until the comparison is done (leaked into
   * the caller's list below, freed there) */
  names[63] = (char *)s;
  return rc;
}

static int is_length(const ucase *c, const char *name) {
  for (int i = 0; c->lengths[i]; i++)
    if (!strcmp(c->lengths[i], name)) return 1;
  return 0;
}

static void compare(const ucase *c, const char *mode) {
  double *xm = calloc(2 * 64 * NOUT, sizeof(double)), *xmm = xm + 64 * NOUT;
  char *nm[64] = {0}, *nmm[64] = {0};
  int nx = 0, nx2 = 0;
  int rc = run(c, 0, mode, xm, &nx, nm);
  if (rc == AP_OK) rc = run(c, 1, mode, xmm, &nx2, nmm);
  if (rc == AP_OK && nx == nx2 && nx < 63) {
    double worst = 0.0;   /* largest difference / bound */
    for (int i = 0; i < nx; i++) {
      double f = is_length(c, nm[i]) ? 1e-3 : 1.0, X = 0.0, d = 0.0;
      for (int o = 0; o < NOUT; o++) {
        X = fmax(X, fabs(xm[o * nx + i]));
        d = fmax(d, fabs(xm[o * nx + i] - f * xmm[o * nx + i]));
      }
      double bound = 2 * 10 * (RTOL * X + ATOL_M);
      AP_CHECK_LE(d, bound);
      worst = fmax(worst, d / bound);
    }
    printf("%-18s %-9s metres vs millimetres / 1000: largest difference %.2f of its bound\n",
           c->file, mode, worst);
  }
  if (nm[63]) ap_scene_free((ap_scene *)nm[63]);
  if (nmm[63]) ap_scene_free((ap_scene *)nmm[63]);
  free(xm);
}

/* ---- 2. redundant drives in six systems of units ----------------------------------------- */

typedef struct usys {
  const char *name;
  double L, T, M;   /* the unit of length, time and mass in metres, seconds and kilograms^-1:
                       a length of 1 m is L units, 1 s is T units, 1 kg is M units */
} usys;

static const usys UNITS[] = {{"m", 1, 1, 1},    {"mm", 1e3, 1, 1}, {"um", 1e6, 1, 1},
                             {"km", 1e-3, 1, 1}, {"ms", 1, 1e3, 1}, {"g", 1, 1, 1e3}};
#define NUNITS (int)(sizeof UNITS / sizeof UNITS[0])

enum { DRIVES, TURNS };
enum { CONSISTENT, INCONSISTENT, GAMMA_ONLY, AT_REST };
#define NSETS 24

/* The overrides of scene sc in units u with the second drive off by delta (case kind). */
static int overrides(int sc, const usys *u, int kind, double delta, char buf[NSETS][96],
                     double *atol) {
  double L = u->L, T = u->T, M = u->M, L2 = L * L;
  int n = 0;
#define SET(...) snprintf(buf[n++], 96, __VA_ARGS__)
  *atol = 1e-12 * fmin(fmin(L, 1.0), fmin(L / T, 1.0 / T));
  SET("simulation.rtol=%.17g", 1e-9), SET("simulation.atol=%.17g", *atol);
  SET("simulation.t_end=%.17g", 2 * T);
  if (sc == DRIVES) {
    double v0 = kind == AT_REST ? 0.0 : 0.01 * L / T, a = kind == GAMMA_ONLY ? 0.01 * L / (T * T) : 0;
    SET("bodies.cart.mass=%.17g", 2 * M), SET("bodies.bob.mass=%.17g", 0.5 * M);
    for (int i = 0; i < 3; i++) SET("bodies.cart.inertia.%d=%.17g", i, 0.01 * M * L2);
    SET("bodies.bob.inertia.0=%.17g", 0.004 * M * L2), SET("bodies.bob.inertia.1=%.17g", 0.004 * M * L2);
    SET("bodies.bob.inertia.2=%.17g", 0.001 * M * L2), SET("bodies.bob.com.2=%.17g", -0.3 * L);
    SET("effects.gravity.g.2=%.17g", -9.81 * L / (T * T));
    SET("constraints.drive.value=%.17g + %.17g*t", v0, a);
    if (kind == GAMMA_ONLY) SET("constraints.drive_again.value=%.17g + %.17g*t", v0, a * (1 + delta));
    else SET("constraints.drive_again.value=%.17g + %.17g*t", v0 * (1 + delta), a);
    SET("initial.cart.rate=%.17g", v0);
  } else {
    double w = 0.8 / T;
    SET("bodies.skate.mass=%.17g", 1.5 * M), SET("bodies.skate.com.0=%.17g", 0.2 * L);
    SET("bodies.skate.inertia.0=%.17g", 0.02 * M * L2), SET("bodies.skate.inertia.1=%.17g", 0.05 * M * L2);
    SET("bodies.skate.inertia.2=%.17g", 0.06 * M * L2);
    SET("constraints.blade.point.0=%.17g", 0.5 * L);
    SET("constraints.turn.value=%.17g", w), SET("constraints.turn_again.value=%.17g", w * (1 + delta));
    SET("initial.skate.vx=%.17g", 1.0 * L / T), SET("initial.skate.vy=%.17g", -0.4 * L / T);
    SET("initial.skate.heading_rate=%.17g", w);
  }
#undef SET
  return n;
}

/* The factor of a coordinate or speed of scene sc in units u (a length: L, a linear speed: L/T,
 * an angular speed: 1/T, an angle: 1). */
static double factor(const char *name, const usys *u) {
  int len = strstr(name, ".pos") || strstr(name, ".x") || strstr(name, ".y");
  int rate = strstr(name, "_dot") != NULL;
  return (len ? u->L : 1.0) / (rate ? u->T : 1.0);
}

typedef struct urun {
  int rc, nx;
  double x[5][8];   /* t = 0, 0.5 T, ..., 2 T */
  char names[8][32], msg[512];
} urun;

static void urun_scene(int sc, const usys *u, int kind, double delta, const char *mode,
                       const char *path, urun *r) {
  char file[1200], buf[NSETS][96], sm[64], sp[64], msg[1024] = "";
  const char *sets[NSETS + 2];
  double atol = 0;
  int ns = overrides(sc, u, kind, delta, buf, &atol);
  for (int i = 0; i < ns; i++) sets[i] = buf[i];
  snprintf(sm, sizeof sm, "simulation.mode=%s", mode), snprintf(sp, sizeof sp, "simulation.path=%s", path);
  sets[ns++] = sm, sets[ns++] = sp;
  memset(r, 0, sizeof *r);
  ct_source(file, sizeof file, "tests/scenes", sc == DRIVES ? "units_drives.yaml" : "units_turns.yaml");
  ap_scene *s = NULL;
  r->rc = ap_scene_load(file, sets, ns, &s, msg, sizeof msg);
  AP_CHECK_EQ_INT(r->rc, AP_OK);
  if (r->rc != AP_OK) return (void)fprintf(stderr, "%s: %s\n", file, msg);
  const ap_model *m = ap_scene_model(s);
  int n = ap_model_n(m), k = ap_model_k(m);
  r->nx = n + k;
  for (int i = 0; i < n + k && i < 8; i++)
    snprintf(r->names[i], 32, "%s", i < n ? ap_model_coord_name(m, i) : ap_model_speed_name(m, i - n));
  ap_scene_run sr;
  ap_scene_get_run(s, &sr);
  double q0[8] = {0}, v0[8] = {0};
  ap_sim *sim = NULL;
  if (sc == TURNS) {   /* the state itself (the scene's, which the scene's own check of the */
    v0[0] = 1.0 * u->L / u->T, v0[1] = -0.4 * u->L / u->T, v0[2] = 0.8 / u->T;  /* speeds */
  } else {             /* would refuse first): the rows are judged by ap_sim_create */
    r->rc = ap_scene_initial_state(s, q0, v0, NULL, 0, msg, sizeof msg);
  }
  if (r->rc == AP_OK) r->rc = ap_sim_create(m, &sr.sim, 0.0, q0, v0, &sim, msg, sizeof msg);
  for (int o = 0; r->rc == AP_OK && o < 5; o++) {
    if (o > 0 && (r->rc = ap_sim_advance(sim, 0.5 * o * u->T)) != AP_OK)
      snprintf(msg, sizeof msg, "%s", ap_sim_message(sim));
    for (int i = 0; i < n + k && i < 8; i++)
      r->x[o][i] = (i < n ? ap_sim_q(sim)[i] : ap_sim_v(sim)[i - n]) / factor(r->names[i], u);
  }
  snprintf(r->msg, sizeof r->msg, "%s", msg);
  ap_sim_free(sim);
  ap_scene_free(s);
}

static const char *const SCENE_NAMES[2] = {"units_drives", "units_turns"};
static const char *const KIND_NAMES[4] = {"consistent", "inconsistent", "gamma only", "at rest"};

/* Consistent cases: every unit runs and moves as the metre run within the bound. */
static void same_motion(int sc, int kind, const char *mode) {
  static urun ref, r;
  urun_scene(sc, &UNITS[0], kind, 1e-9, mode, "dense", &ref);
  AP_CHECK_EQ_INT(ref.rc, AP_OK);
  double worst = 0.0;
  for (int u = 1; u < NUNITS && ref.rc == AP_OK; u++) {
    /* Not checked: the skate in micrometres. Its knife edge's row has the lever arm 5e5 um
     * beside entries 1, and the rank of A is decided relative to its largest pivot
     * (|R_ii| > rank_rtol |R_00|, A not equilibrated): the prescribed rates' pivots, 4e-12 of
     * it, count as zero and both rates are refused (docs/api.md "Tolerances"). */
    if (sc == TURNS && !strcmp(UNITS[u].name, "um")) continue;
    urun_scene(sc, &UNITS[u], kind, 1e-9, mode, "dense", &r);
    AP_CHECK_EQ_INT(r.rc, AP_OK);
    if (r.rc != AP_OK) {
      printf("%-12s %-10s %-9s in %s: refused: %s\n", SCENE_NAMES[sc], KIND_NAMES[kind], mode,
             UNITS[u].name, r.msg);
      continue;
    }
    for (int i = 0; i < r.nx; i++) {
      double X = 0.0, d = 0.0;
      for (int o = 0; o < 5; o++) X = fmax(X, fabs(ref.x[o][i])), d = fmax(d, fabs(ref.x[o][i] - r.x[o][i]));
      double bound = 2 * 10 * (1e-9 * X + 1e-12);
      AP_CHECK_LE(d, bound);
      worst = fmax(worst, d / bound);
    }
  }
  printf("%-12s %-10s %-9s mm, %skm, ms, g vs m: largest difference %.2f of its bound\n",
         SCENE_NAMES[sc], KIND_NAMES[kind], mode, sc == TURNS ? "" : "um, ", worst);
}

/* Inconsistent cases: every unit (and the tree path) refuses with AP_ERR_INCONSISTENT. */
static void same_refusal(int sc, int kind, const char *path) {
  static urun r;
  int refused = 0;
  char ran[128] = "";
  for (int u = 0; u < NUNITS; u++) {
    /* Not checked: milliseconds. The floor of a row's terms (core.h: 1 model length scale, or
     * 1 rad, per second: it keeps the round-off of a0 and gamma from counting) is the one
     * tolerance with a unit of time, and these drives (0.01 m/s, the skate's 0.8 rad/s) are
     * below it: in milliseconds it is 1000 times larger and the rows are dropped. */
    if (!strcmp(UNITS[u].name, "ms")) continue;
    urun_scene(sc, &UNITS[u], kind, 1e-6, "minimal", path, &r);
    /* AP_ERR_INCONSISTENT from the run, or from the scene's initial state ("impossible
     * initial state: ... inconsistent") */
    int ok = r.rc != AP_OK && strstr(r.msg, "inconsistent") != NULL;
    AP_CHECK(ok);
    if (ok) refused++;
    else snprintf(ran + strlen(ran), sizeof ran - strlen(ran), " %s (%d)", UNITS[u].name, r.rc);
    if (u == 0) printf("%-12s %-10s %s path, m: %s\n", SCENE_NAMES[sc], KIND_NAMES[kind], path, r.msg);
  }
  printf("%-12s %-10s %s path: refused in %d of %d units (m, mm, um, km, g)%s%s\n",
         SCENE_NAMES[sc], KIND_NAMES[kind], path, refused, NUNITS - 1, *ran ? "; not in" : "",
         ran);
}

int main(void) {
  ct_find_source(ct_src, sizeof ct_src);
  for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
    compare(&CASES[i], "minimal");
    compare(&CASES[i], "projected");
  }
  for (int sc = DRIVES; sc <= TURNS; sc++) {
    same_motion(sc, CONSISTENT, "minimal");
    same_motion(sc, CONSISTENT, "projected");
    same_refusal(sc, INCONSISTENT, "dense");
  }
  /* The tree path judges all rows at once against the largest row's terms (it forms no A to
   * take the dropped rows apart): the skate's rates in rad/s beside its knife edge in m/s are
   * not checked there. */
  same_refusal(DRIVES, INCONSISTENT, "tree");
  same_refusal(DRIVES, GAMMA_ONLY, "dense");
  same_motion(DRIVES, AT_REST, "minimal");
  return ap_check_finish("units");
}
