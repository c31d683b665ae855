/* Compiled models (docs/compiled.md) against the interpreted path, their reference.
 *
 * Every example scene and a few test scenes (a chain of tops on ball joints, loops, friction)
 * are loaded twice, with simulation.compile: never and always. Checked, within 1e-13 relative:
 *   - one ap_forward at the initial state and at three perturbed states (q, v moved by up to
 *     5%): v', q', g, h, A, a0, B, b0, w, G (its Cholesky factor), Phi, e'' (the generated
 *     code performs the interpreted code's operations in the same order, so the two agree to
 *     the last bit up to the sign of a zero); the last state with condition estimates, which
 *     send the acceleration stage back to the core's own (the compiled stage's fallback);
 *   - one ap_forward more on another partition than ap_partition's (the compiled acceleration
 *     stage's variant for the scene's initial partition then hands over to the generic one);
 *   - a whole run of up to 0.5 s with the scene's settings: the final q and v and the number of
 *     steps.
 * A model the generator does not take stays interpreted with a notice naming why (counted; none
 * of these; the tree path is such a model).
 * Values that are not finite (a NaN coordinate or speed, a speed whose bias overflows) stop
 * ap_forward with the interpreted path's status and message (the array and entry named).
 * Fallback: with no C compiler on PATH the scene loads interpreted with a one-line notice and
 * runs. Cache: a corrupt cached shared object is rejected and rebuilt; the cache directory is
 * created 0700. The cache is a fresh directory under /tmp (XDG_CACHE_HOME). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <appell/appell.h>

#include "check.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

#define RTOL 1e-13

static int n_compiled, n_interpreted;

static ap_scene *load(const char *path, const char *mode) {
  char set[64], msg[1024] = "";
  snprintf(set, sizeof set, "simulation.compile=%s", mode);
  const char *sets[] = {set};
  ap_scene *sc = NULL;
  if (ap_scene_load(path, sets, 1, &sc, msg, sizeof msg) != AP_OK) return NULL;
  return sc;
}

/* max |a - b| / (scale of a) over n entries. */
static double rel_diff(const double *a, const double *b, int n) {
  double d = 0.0, s = 1e-300;
  for (int i = 0; i < n; i++) d = fmax(d, fabs(a[i] - b[i])), s = fmax(s, fabs(a[i]));
  return d / s;
}

static int n_swapped;   /* evaluations on a partition other than the initial state's */

/* Another partition than ap_partition's: its dependent speed a swapped with its independent
 * speed r + c (the independent ones kept ascending, nullspace.c's invariant). */
static void swap_partition(ap_data *d, int k, int a, int c) {
  int r = d->rank, t = d->perm[a];
  d->perm[a] = d->perm[r + c], d->perm[r + c] = t;
  for (int i = r + 1; i < k; i++)
    for (int j = i; j > r && d->perm[j] < d->perm[j - 1]; j--)
      t = d->perm[j], d->perm[j] = d->perm[j - 1], d->perm[j - 1] = t;
}

/* The first such swap on which the interpreted ap_forward succeeds (the dependent block
 * regular): 1 with d on it, or 0 (d's partition then ap_partition's). */
static int other_partition(const ap_model *m, ap_data *d, int *swap_ac) {
  int k = ap_model_k(m), r = d->rank, *perm = malloc(sizeof(int) * (size_t)(k + 1));
  for (int i = 0; perm && i < k; i++) perm[i] = d->perm[i];
  for (int a = 0; perm && r > 0 && a < r; a++)
    for (int c = 0; c < k - r; c++) {
      swap_partition(d, k, a, c);
      if (ap_forward(m, d) == AP_OK) return swap_ac[0] = a, swap_ac[1] = c, free(perm), 1;
      for (int i = 0; i < k; i++) d->perm[i] = perm[i];
      d->rank = r;
    }
  free(perm);
  return 0;
}

/* cond: ask for condition estimates, which the compiled acceleration stage leaves to the
 * core's (its fallback, checked the same way). swap: evaluate on another partition
 * (swap_partition): the compiled acceleration stage's variant for the scene's initial
 * partition hands over to the generic one. */
static double forward_diff(const ap_model *mi, const ap_model *mc, const double *q,
                           const double *v, double t, int cond, int swap) {
  int n = ap_model_n(mi), k = ap_model_k(mi), b = ap_model_b(mi);
  ap_data *di = NULL, *dc = NULL;
  double worst = 0.0;
  if (ap_data_create(mi, &di) != AP_OK || ap_data_create(mc, &dc) != AP_OK) return INFINITY;
  ap_data *ds[2] = {di, dc};
  const ap_model *ms[2] = {mi, mc};
  int rc[2], ac[2] = {0, 0};
  for (int s = 0; s < 2; s++) {
    memcpy(ds[s]->q, q, sizeof *q * (size_t)n);
    memcpy(ds[s]->v, v, sizeof *v * (size_t)k);
    ds[s]->t = t;
    ds[s]->estimate_cond = cond;
    rc[s] = ap_partition(ms[s], ds[s]);
    if (swap && rc[s] == AP_OK && s == 0) swap = other_partition(mi, di, ac);
    if (swap && rc[s] == AP_OK && s == 1) swap_partition(dc, k, ac[0], ac[1]);
    if (rc[s] == AP_OK) rc[s] = ap_forward(ms[s], ds[s]);
  }
  if (rc[0] != rc[1]) worst = INFINITY;
  else if (rc[0] == AP_OK && ap_model_path(mi) == AP_PATH_DENSE) {
    worst = fmax(rel_diff(di->vdot, dc->vdot, k), rel_diff(di->qdot, dc->qdot, n));
    worst = fmax(worst, rel_diff(di->g, dc->g, k * k));
    worst = fmax(worst, rel_diff(di->h, dc->h, k));
    worst = fmax(worst, rel_diff(di->A, dc->A, b * k));
    worst = fmax(worst, rel_diff(di->a0, dc->a0, b));
    int l = di->l;   /* the basis and the acceleration stage's objects (compiled too) */
    if (dc->l != l) worst = INFINITY;
    else if (b > 0)
      worst = fmax(worst, fmax(rel_diff(di->B, dc->B, k * l),
                               fmax(rel_diff(di->b0, dc->b0, k), rel_diff(di->w, dc->w, k))));
    if (dc->l == l && l > 0)
      worst = fmax(worst, fmax(rel_diff(di->G, dc->G, l * l),
                               fmax(rel_diff(di->Phi, dc->Phi, l), rel_diff(di->edd, dc->edd, l))));
  } else if (rc[0] == AP_OK) {
    worst = fmax(rel_diff(di->vdot, dc->vdot, k), rel_diff(di->qdot, dc->qdot, n));
  }
  if (swap && rc[0] == AP_OK) n_swapped++;
  ap_data_free(di), ap_data_free(dc);
  return worst;
}

/* The run of one scene to min(t_end, t0 + 0.5): final state and step count. */
static int run(ap_scene *sc, double *x, long *steps) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m);
  ap_scene_run r;
  ap_scene_get_run(sc, &r);
  char msg[1024];
  ap_sim *sim = NULL;
  int rc = ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_create(m, &r.sim, r.t0, x, x + n, &sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_scene_add_events(sc, sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_advance(sim, fmin(r.t_end, r.t0 + 0.5));
  if (sim) {
    memcpy(x, ap_sim_q(sim), sizeof *x * (size_t)n);
    memcpy(x + n, ap_sim_v(sim), sizeof *x * (size_t)ap_model_k(m));
    ap_sim_stats st;
    ap_sim_get_stats(sim, &st);
    *steps = st.steps;
  }
  ap_sim_free(sim);
  return rc;
}

static void compare_scene(const char *path) {
  ap_scene *si = load(path, "never"), *sc = load(path, "always");
  if (!si || !sc) {   /* scenes that do not load (tests of errors) are not models */
    ap_scene_free(si), ap_scene_free(sc);
    return;
  }
  const ap_model *mi = ap_scene_model(si), *mc = ap_scene_model(sc);
  AP_CHECK(!ap_model_is_compiled(mi));
  if (!ap_model_is_compiled(mc)) {
    printf("  %-40s interpreted: %s\n", strrchr(path, '/') + 1, ap_scene_compile_notice(sc));
    AP_CHECK(ap_scene_compile_notice(sc)[0] != '\0');
    n_interpreted++;
    ap_scene_free(si), ap_scene_free(sc);
    return;
  }
  n_compiled++;
  int n = ap_model_n(mi), k = ap_model_k(mi);
  double *x = calloc((size_t)(2 * (n + k)), sizeof *x), *y = x + n + k, worst = 0.0;
  char msg[1024];
  ap_scene_run r;
  ap_scene_get_run(si, &r);
  if (ap_scene_initial_state(si, x, x + n, NULL, 0, msg, sizeof msg) == AP_OK) {
    for (int trial = 0; trial < 5; trial++) {
      for (int i = 0; i < n + k && trial; i++)   /* deterministic moves of up to 5% */
        y[i] = x[i] * (1 + 0.05 * sin(7.0 * i + trial)) + 0.01 * cos(3.0 * i * trial);
      if (!trial) memcpy(y, x, sizeof *x * (size_t)(n + k));
      worst = fmax(worst, forward_diff(mi, mc, y, y + n, r.t0, trial == 3, trial == 4));
    }
  }
  long si_steps = -1, sc_steps = -2;
  int rci = run(si, x, &si_steps), rcc = run(sc, y, &sc_steps);
  double wrun = rel_diff(x, y, n + k);
  printf("  %-40s compiled: forward %.2g, run %.2g (%ld steps, status %d)\n",
         strrchr(path, '/') + 1, worst, wrun, si_steps, rci);
  AP_CHECK_LE(worst, RTOL);
  AP_CHECK(rci == rcc);
  AP_CHECK(si_steps == sc_steps);
  AP_CHECK_LE(wrun, RTOL);
  free(x);
  ap_scene_free(si), ap_scene_free(sc);
}

/* A model without effects whose compiled code writes Q in full (the core does not zero it) and
 * an input torque added to Q at every evaluation: the runs stay equal (an input that piled up
 * in Q would not). */
static void input_run(const char *path) {
  ap_scene *sc[2] = {load(path, "never"), load(path, "always")};
  double x[2][64];
  for (int s = 0; s < 2; s++) {
    const ap_model *m = ap_scene_model(sc[s]);
    int n = ap_model_n(m), k = ap_model_k(m);
    const char *names[] = {"wheel.angle_dot", NULL};
    char msg[1024];
    ap_scene_run r;
    ap_scene_get_run(sc[s], &r);
    ap_sim *sim = NULL;
    AP_CHECK(n + k <= 64);
    AP_CHECK(ap_scene_initial_state(sc[s], x[s], x[s] + n, NULL, 0, msg, sizeof msg) == AP_OK);
    AP_CHECK(ap_sim_create(m, &r.sim, r.t0, x[s], x[s] + n, &sim, msg, sizeof msg) == AP_OK);
    AP_CHECK(ap_sim_declare_inputs(sim, names) == AP_OK);
    AP_CHECK(ap_sim_set_input(sim, names[0], 0.02) == AP_OK);
    AP_CHECK(ap_sim_advance(sim, r.t0 + 0.5) == AP_OK);
    memcpy(x[s], ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(x[s] + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
    ap_sim_free(sim);
  }
  int nk = ap_model_n(ap_scene_model(sc[0])) + ap_model_k(ap_scene_model(sc[0]));
  double d = rel_diff(x[0], x[1], nk);
  printf("  input torque without effects: compiled %d, run %.2g\n",
         ap_model_is_compiled(ap_scene_model(sc[1])), d);
  AP_CHECK(ap_model_is_compiled(ap_scene_model(sc[1])));
  AP_CHECK_LE(d, RTOL);
  ap_scene_free(sc[0]), ap_scene_free(sc[1]);
}

static int by_name(const struct dirent **a, const struct dirent **b) {
  return strcmp((*a)->d_name, (*b)->d_name);
}

static void compare_dir(const char *dir) {
  struct dirent **list = NULL;
  int count = scandir(dir, &list, NULL, by_name);
  for (int i = 0; i < count; i++) {
    const char *nm = list[i]->d_name;
    size_t len = strlen(nm);
    char path[2048];
    snprintf(path, sizeof path, "%s/%s", dir, nm);
    if (len > 5 && strcmp(nm + len - 5, ".yaml") == 0) compare_scene(path);
    free(list[i]);
  }
  free(list);
}

/* The only shared object in the cache directory, into so. */
static int find_so(const char *dir, char *so, size_t len) {
  DIR *d = opendir(dir);
  struct dirent *e;
  int found = 0;
  while (d && (e = readdir(d)))
    if (strstr(e->d_name, ".so")) snprintf(so, len, "%s/%s", dir, e->d_name), found++;
  if (d) closedir(d);
  return found;
}

/* A value that is not finite (a NaN coordinate, a speed of 1e200 whose bias overflows, a NaN
 * speed) stops ap_forward with the same status and the same message (array, entry, t) in both
 * paths: the compiled path's one check per stage hands over to the core's per-array checks. */
static void not_finite(const char *path) {
  ap_scene *si = load(path, "never"), *sc = load(path, "always");
  AP_CHECK(si && sc && ap_model_is_compiled(ap_scene_model(sc)));
  if (!si || !sc) return;
  const ap_model *ms[2] = {ap_scene_model(si), ap_scene_model(sc)};
  int n = ap_model_n(ms[0]), k = ap_model_k(ms[0]);
  for (int c = 0; c < 3; c++) {
    ap_data *d[2] = {NULL, NULL};
    int rc[2] = {-1, -2};
    char msg[1024];
    for (int s = 0; s < 2; s++) {
      if (ap_data_create(ms[s], &d[s]) != AP_OK) break;
      ap_scene_initial_state(si, d[s]->q, d[s]->v, NULL, 0, msg, sizeof msg);
      rc[s] = ap_partition(ms[s], d[s]);
      if (c == 0) d[s]->q[n - 1] = NAN;       /* the kinematics */
      else if (c == 1)                        /* the bias overflows */
        for (int i = 0; i < k; i++) d[s]->v[i] = 1e200;
      else d[s]->v[k - 1] = NAN;              /* the bias */
      d[s]->t = 0.25;
      if (rc[s] == AP_OK) rc[s] = ap_forward(ms[s], d[s]);
    }
    if (d[0] && d[1]) {
      printf("  not finite (%d): %d \"%s\" | %d \"%s\"\n", c, rc[0], d[0]->msg, rc[1],
             d[1]->msg);
      AP_CHECK(rc[0] == rc[1] && strcmp(d[0]->msg, d[1]->msg) == 0);
      AP_CHECK(c == 0 || (rc[0] == AP_ERR_NAN && strstr(d[0]->msg, "produced")));
    } else {
      AP_CHECK(0);
    }
    ap_data_free(d[0]), ap_data_free(d[1]);
  }
  ap_scene_free(si), ap_scene_free(sc);
}

/* A user expression that stops being finite mid-run: the same status, time and message. */
static void nan_run(const char *path) {
  ap_scene *sc[2] = {load(path, "never"), load(path, "always")};
  AP_CHECK(sc[0] && sc[1] && ap_model_is_compiled(ap_scene_model(sc[1])));
  char msg[2][1024] = {"", ""};
  int rc[2] = {0, 0};
  double t[2] = {0, 0};
  for (int s = 0; s < 2 && sc[0] && sc[1]; s++) {
    const ap_model *m = ap_scene_model(sc[s]);
    int n = ap_model_n(m);
    double x[64];
    ap_scene_run r;
    ap_scene_get_run(sc[s], &r);
    ap_sim *sim = NULL;
    rc[s] = ap_scene_initial_state(sc[s], x, x + n, NULL, 0, msg[s], sizeof msg[s]);
    if (rc[s] == AP_OK) rc[s] = ap_sim_create(m, &r.sim, r.t0, x, x + n, &sim, msg[s], 1024);
    if (rc[s] == AP_OK) rc[s] = ap_sim_advance(sim, r.t_end);
    if (sim) snprintf(msg[s], sizeof msg[s], "%s", ap_sim_message(sim)), t[s] = ap_sim_time(sim);
    ap_sim_free(sim);
  }
  printf("  NaN torque: %d at t = %.17g \"%s\" | %d at t = %.17g \"%s\"\n", rc[0], t[0],
         msg[0], rc[1], t[1], msg[1]);
  AP_CHECK(rc[0] != AP_OK && rc[0] == rc[1] && t[0] == t[1] && strcmp(msg[0], msg[1]) == 0);
  AP_CHECK(strstr(msg[0], "nan") != NULL);
  ap_scene_free(sc[0]), ap_scene_free(sc[1]);
}

static void fallback_and_cache(const char *cache) {
  char disk[1200], dir[1500], so[1800], old_path[4096];
  snprintf(disk, sizeof disk, "%s/examples/scenes/rolling_disk.yaml", AP_SRCDIR);
  /* no compiler: a fresh cache and a PATH without cc */
  char fresh[1400];
  snprintf(fresh, sizeof fresh, "%s/nocc", cache);
  setenv("XDG_CACHE_HOME", fresh, 1);
  snprintf(old_path, sizeof old_path, "%s", getenv("PATH") ? getenv("PATH") : "/usr/bin:/bin");
  setenv("PATH", "/nonexistent", 1);
  ap_scene *sc = load(disk, "always");
  setenv("PATH", old_path, 1);
  AP_CHECK(sc && !ap_model_is_compiled(ap_scene_model(sc)));
  const char *note = sc ? ap_scene_compile_notice(sc) : "";
  printf("  no compiler: \"%s\"\n", note);
  AP_CHECK(strstr(note, "runs interpreted") && strstr(note, "no C compiler") &&
           !strchr(note, '\n'));
  double x[64];
  long steps = 0;
  AP_CHECK(sc && run(sc, x, &steps) == AP_OK && steps > 0);
  ap_scene_free(sc);

  /* the cache directory: 0700; a corrupt shared object is rebuilt */
  snprintf(fresh, sizeof fresh, "%s/corrupt", cache);
  setenv("XDG_CACHE_HOME", fresh, 1);
  snprintf(dir, sizeof dir, "%s/appell", fresh);
  sc = load(disk, "always");
  AP_CHECK(sc && ap_model_is_compiled(ap_scene_model(sc)));
  ap_scene_free(sc);   /* unloads the shared object */
  struct stat st;
  AP_CHECK(stat(dir, &st) == 0 && (st.st_mode & 0777) == 0700);
  AP_CHECK(find_so(dir, so, sizeof so) == 1);
  FILE *f = fopen(so, "wb");
  if (f) fputs("not a shared object\n", f), fclose(f);
  sc = load(disk, "always");
  AP_CHECK(sc && ap_model_is_compiled(ap_scene_model(sc)));
  ap_scene_free(sc);
  char head[4] = {0};
  f = fopen(so, "rb");
  AP_CHECK(f && fread(head, 1, 4, f) == 4 && memcmp(head, "\177ELF", 4) == 0);
  if (f) fclose(f);

  /* the tree path stays interpreted, with a notice */
  char msg[1024];
  const char *tree[] = {"simulation.compile=always", "simulation.path=tree"};
  AP_CHECK(ap_scene_load(disk, tree, 2, &sc, msg, sizeof msg) == AP_OK &&
           !ap_model_is_compiled(ap_scene_model(sc)) &&
           strstr(ap_scene_compile_notice(sc), "tree path") != NULL);
  ap_scene_free(sc);

  /* APPELL_COMPILE is the default of a scene that does not say */
  setenv("APPELL_COMPILE", "always", 1);
  AP_CHECK(ap_scene_load(disk, NULL, 0, &sc, msg, sizeof msg) == AP_OK &&
           ap_model_is_compiled(ap_scene_model(sc)));
  ap_scene_free(sc);
  unsetenv("APPELL_COMPILE");
}

int main(void) {
  char cache[] = "/tmp/appell-test-compiled-XXXXXX", dir[1200];
  if (!mkdtemp(cache)) return printf("cannot make a temporary directory\n"), 1;
  setenv("XDG_CACHE_HOME", cache, 1);
  unsetenv("APPELL_COMPILE");
  snprintf(dir, sizeof dir, "%s/examples/scenes", AP_SRCDIR);
  compare_dir(dir);
  const char *tests[] = {"modes_double_top.yaml", "modes_free_balls.yaml",
                         "act_motor_angle_ball.yaml", "difftest/rolling_knife.yaml",
                         "difftest/seed_17.yaml", "difftest/locked_at_rest.yaml",
                         "compiled_contacts.yaml"};
  for (size_t i = 0; i < sizeof tests / sizeof tests[0]; i++) {
    snprintf(dir, sizeof dir, "%s/tests/scenes/%s", AP_SRCDIR, tests[i]);
    compare_scene(dir);
  }
  printf("compiled %d models, %d stayed interpreted; %d evaluated on another partition\n",
         n_compiled, n_interpreted, n_swapped);
  AP_CHECK(n_compiled >= 30);
  AP_CHECK(n_swapped >= 10);
  snprintf(dir, sizeof dir, "%s/examples/scenes/rolling_disk.yaml", AP_SRCDIR);
  not_finite(dir);
  snprintf(dir, sizeof dir, "%s/examples/scenes/bicycle.yaml", AP_SRCDIR);
  not_finite(dir);
  snprintf(dir, sizeof dir, "%s/examples/scenes/sleigh_wheel.yaml", AP_SRCDIR);
  input_run(dir);
  snprintf(dir, sizeof dir, "%s/tests/scenes/compiled_nan_torque.yaml", AP_SRCDIR);
  nan_run(dir);
  fallback_and_cache(cache);
  char cmd[1300];   /* our own temporary directory, made by mkdtemp above */
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", cache);
  if (system(cmd) != 0) printf("could not remove %s\n", cache);
  return ap_check_finish("compiled");
}
