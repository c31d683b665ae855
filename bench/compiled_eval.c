/* compiled_eval: one evaluation (ap_forward, as the minimal-mode integrator calls it) of the
 * rolling disk, the differential-drive robot and the Whipple bicycle, interpreted and compiled
 * (docs/compiled.md), at each scene's initial state; the hand-reduced rolling disk's
 * right-hand side beside them; and the compile time of each model (code generation, cc,
 * dlopen) into a fresh cache, and its load from the warm cache.
 *
 * Time: median over blocks of `reps` evaluations (thread CPU time, ns per evaluation; noisy on
 * a shared machine). Compile: CPU time of this process and the compiler (getrusage of the
 * children), and the wall time beside it. Instructions (stable): under callgrind, one function per side,
 *   valgrind --tool=callgrind --toggle-collect=eval_interp build/bench/compiled_eval --only disk
 *   (eval_compiled, eval_hand likewise); divide the total by the printed evaluation count.
 * Usage: compiled_eval [--reps N] [--blocks N] [--only disk|robot|bicycle] [--compile N]
 * (--compile N: only the cold compiles, N of each model, their median and least CPU and wall
 * time and the load average)
 * Run with OPENBLAS_NUM_THREADS=1; XDG_CACHE_HOME picks the cache the runs load from. */
#define _DEFAULT_SOURCE   /* getloadavg */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "appell/appell.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

static double clock_s(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static double now(void) { return clock_s(CLOCK_THREAD_CPUTIME_ID); }

/* CPU seconds of this process and of its waited-for children (the compiler). */
static double cpu_all(void) {
  struct rusage ru;
  getrusage(RUSAGE_CHILDREN, &ru);
  return clock_s(CLOCK_PROCESS_CPUTIME_ID) + (double)ru.ru_utime.tv_sec +
         (double)ru.ru_stime.tv_sec + 1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

static void die(const char *what, const char *msg) {
  fprintf(stderr, "compiled_eval: %s: %s\n", what, msg);
  exit(1);
}

static ap_scene *load(const char *file, const char *mode) {
  char path[1200], set[64], msg[1024] = "";
  snprintf(path, sizeof path, "%s/examples/scenes/%s", AP_SRCDIR, file);
  snprintf(set, sizeof set, "simulation.compile=%s", mode);
  const char *sets[] = {set};
  ap_scene *sc = NULL;
  if (ap_scene_load(path, sets, 1, &sc, msg, sizeof msg) != AP_OK) die(file, msg);
  return sc;
}

/* A data at the scene's initial state, partitioned. */
static ap_data *prepare(ap_scene *sc) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m);
  ap_data *d = NULL;
  char msg[1024];
  ap_scene_run r;
  ap_scene_get_run(sc, &r);
  if (ap_data_create(m, &d) != AP_OK) die("data", "out of memory");
  if (ap_scene_initial_state(sc, d->q, d->v, NULL, 0, msg, sizeof msg) != AP_OK)
    die("initial state", msg);
  (void)n;
  d->t = r.t0;
  if (ap_partition(m, d) != AP_OK || ap_forward(m, d) != AP_OK) die("forward", "failed");
  return d;
}

__attribute__((noinline)) void eval_interp(const ap_model *m, ap_data *d, int reps) {
  for (int r = 0; r < reps; r++) ap_forward(m, d);
}

__attribute__((noinline)) void eval_compiled(const ap_model *m, ap_data *d, int reps) {
  for (int r = 0; r < reps; r++) ap_forward(m, d);
}

/* The rolling disk by hand (docs/references.md §4; bench/wp_problems.c derives it): y = (x, y,
 * psi, theta, w1, w2, w3), the scene's m = 1, r = 0.5, g = 9.81. */
static void disk_rhs(const double *y, double *yd) {
  const double m = 1.0, r = 0.5, g = 9.81;
  double A = 0.25 * m * r * r, C = 0.5 * m * r * r, mr2 = m * r * r;
  double cp = cos(y[2]), sp = sin(y[2]), ct = cos(y[3]), st = sin(y[3]), tt = st / ct;
  double w1 = y[4], w2 = y[5], w3 = y[6];
  yd[0] = r * (w2 * cp + w1 * ct * sp), yd[1] = r * (w2 * sp - w1 * ct * cp);
  yd[2] = w3 / ct, yd[3] = w1;
  yd[4] = ((C + mr2) * w2 * w3 - A * w3 * w3 * tt + m * g * r * st) / (A + mr2);
  yd[5] = -mr2 * w1 * w3 / (C + mr2);
  yd[6] = w1 * w3 * tt - (C / A) * w1 * w2;
}

__attribute__((noinline)) void eval_hand(int reps, double *sink) {
  volatile double y0 = 0.1;
  double y[7] = {0, 0, y0, 0.2, 0.3, -4.0, 0.5}, yd[7];
  for (int r = 0; r < reps; r++) {
    y[2] = y0 + 1e-9 * r, y[3] = 0.2 + 1e-9 * r;   /* a new state each time: nothing hoisted */
    disk_rhs(y, yd);
    for (int i = 0; i < 7; i++) sink[0] += yd[i];
  }
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* ns per evaluation: median of the blocks. */
static double timed(const ap_model *m, ap_data *d, int compiled, int reps, int blocks) {
  double ns[64], sink = 0;
  for (int b = 0; b <= blocks && b < 64; b++) {
    double t0 = now();
    if (!m) eval_hand(reps, &sink);
    else if (compiled) eval_compiled(m, d, reps);
    else eval_interp(m, d, reps);
    ns[b] = (now() - t0) * 1e9 / reps;
  }
  qsort(ns + 1, (size_t)blocks, sizeof *ns, cmp);   /* block 0 warms up */
  return ns[1 + blocks / 2] + 0 * sink;
}

/* The scene loaded with compile: always (its parsing, the initial partition, generation + cc +
 * dlopen) into a fresh cache, then the load from the warm cache: CPU ms of this process and
 * the compiler (wall: *wall_ms, for the fresh one). */
static void compile_time(const char *file, double *fresh, double *warm, double *wall_ms) {
  char dir[] = "/tmp/appell-bench-cache-XXXXXX";
  const char *old = getenv("XDG_CACHE_HOME");
  char saved[2048] = "";
  if (old) snprintf(saved, sizeof saved, "%s", old);
  if (!mkdtemp(dir)) die("cache", "cannot make a temporary directory");
  setenv("XDG_CACHE_HOME", dir, 1);
  for (int pass = 0; pass < 2; pass++) {
    double t0 = cpu_all(), w0 = clock_s(CLOCK_MONOTONIC);
    ap_scene *sc = load(file, "always");   /* as a run loads it: with the initial partition */
    if (!ap_model_is_compiled(ap_scene_model(sc))) die(file, ap_scene_compile_notice(sc));
    *(pass ? warm : fresh) = (cpu_all() - t0) * 1e3;
    if (!pass) *wall_ms = (clock_s(CLOCK_MONOTONIC) - w0) * 1e3;
    ap_scene_free(sc);
  }
  if (old) setenv("XDG_CACHE_HOME", saved, 1);
  else unsetenv("XDG_CACHE_HOME");
  char sub[2200], path[2600];   /* remove the temporary cache: appell/model-*.so */
  snprintf(sub, sizeof sub, "%s/appell", dir);
  DIR *dd = opendir(sub);
  struct dirent *e;
  while (dd && (e = readdir(dd)))
    if (e->d_name[0] != '.') snprintf(path, sizeof path, "%s/%s", sub, e->d_name), unlink(path);
  if (dd) closedir(dd);
  rmdir(sub), rmdir(dir);
}

/* --compile N: N cold compiles of each model (a fresh cache each), the medians of CPU and wall
 * time, and the load average before and after. */
static void compile_only(int runs, const char *only, const char *const *names,
                         const char *const *files) {
  double load[2][3] = {{0}};
  getloadavg(load[0], 3);
  printf("%-8s %11s %11s %11s %11s   (cold cache, %d runs; median, min)\n", "model",
         "CPU ms", "(min)", "wall ms", "(min)", runs);
  for (int c = 0; c < 3; c++) {
    if (only && strcmp(only, names[c]) != 0) continue;
    double cpu[64], wall[64], warm;
    for (int r = 0; r < runs; r++) compile_time(files[c], &cpu[r], &warm, &wall[r]);
    qsort(cpu, (size_t)runs, sizeof *cpu, cmp), qsort(wall, (size_t)runs, sizeof *wall, cmp);
    printf("%-8s %11.1f %11.1f %11.1f %11.1f\n", names[c], cpu[runs / 2], cpu[0],
           wall[runs / 2], wall[0]);
  }
  getloadavg(load[1], 3);
  printf("load average %.2f %.2f %.2f before, %.2f %.2f %.2f after\n", load[0][0], load[0][1],
         load[0][2], load[1][0], load[1][1], load[1][2]);
}

int main(int argc, char **argv) {
  int reps = 2000, blocks = 9, compile_runs = 0;
  const char *only = NULL;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = atoi(argv[++i]);
    else if (strcmp(argv[i], "--blocks") == 0 && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    else if (strcmp(argv[i], "--compile") == 0 && i + 1 < argc) compile_runs = atoi(argv[++i]);
    else die("usage", "compiled_eval [--reps N] [--blocks N] [--only disk|robot|bicycle] "
             "[--compile N]");
  }
  if (compile_runs < 0 || compile_runs > 63) die("usage", "0 <= compile runs <= 63");
  if (reps < 1 || blocks < 1 || blocks > 63) die("usage", "reps >= 1, 1 <= blocks <= 63");
  static const char *const names[] = {"disk", "robot", "bicycle"};
  static const char *const files[] = {"rolling_disk.yaml", "diff_drive.yaml", "bicycle.yaml"};
  if (compile_runs > 0) return compile_only(compile_runs, only, names, files), 0;
  printf("%-8s %10s %10s %6s %11s %11s %10s   (CPU time; evaluations per side: %d)\n",
         "model", "interp ns", "compil. ns", "ratio", "compile ms", "(wall ms)", "cached ms",
         reps * (blocks + 1));
  for (int c = 0; c < 3; c++) {
    if (only && strcmp(only, names[c]) != 0) continue;
    double fresh = 0, warm = 0, wall = 0;
    if (!only) compile_time(files[c], &fresh, &warm, &wall);   /* not under callgrind (--only) */
    ap_scene *si = load(files[c], "never"), *sc = load(files[c], "always");
    if (!ap_model_is_compiled(ap_scene_model(sc))) die(files[c], ap_scene_compile_notice(sc));
    ap_data *di = prepare(si), *dc = prepare(sc);
    double ti = timed(ap_scene_model(si), di, 0, reps, blocks);
    double tc = timed(ap_scene_model(sc), dc, 1, reps, blocks);
    printf("%-8s %10.1f %10.1f %6.2f %11.1f %11.1f %10.2f\n", names[c], ti, tc, ti / tc, fresh,
           wall, warm);
    ap_data_free(di), ap_data_free(dc);
    ap_scene_free(si), ap_scene_free(sc);
  }
  if (!only || strcmp(only, "disk") == 0)
    printf("%-8s %10.1f   (hand-reduced rolling disk right-hand side)\n", "hand",
           timed(NULL, NULL, 0, reps, blocks));
  return 0;
}
