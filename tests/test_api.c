/* Every public function called with NULL and out-of-range arguments.
 *
 * Each case is one call and the result its header documents for that misuse: AP_ERR_ARG, or
 * a neutral value (NULL, 0, -1, NaN, "", "?", an output left zeroed or untouched). Each case
 * runs in a child process (fork), so a crash is counted instead of ending the test: a case
 * passes when the child exits 0 (documented result), fails as "wrong" when it exits 3, and as
 * "crash" on any other end (a signal, or a sanitizer's report).
 *
 * Coverage is checked against the headers at test time: every function declared AP_API in
 * include/appell/ (argument 1: the source root) must appear in at least one case, and every
 * case must name a declared function; a header that gains a function without a case here
 * fails the test. The fixtures (models, data, a simulation, a scene, a builder) are made once
 * in the parent and inherited by each child. */
#include <dirent.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "api_case.h"

/* ---- the cases (api_cases_low.c, api_cases_high.c) ------------------------------------------ */

int pick = -1;          /* the case a child runs; -1 in the parent (listing) */
int ncase = 0;
const char *case_fn[MAXCASE], *case_what[MAXCASE];

ap_model *BM, *TM, *SM;   /* rolling disk (body model, b = 2), heavy top, sleigh (math) */
ap_data *BD, *TD, *SD;    /* their data; TD is the wrong data for BM and SM */
ap_sim *S;                /* the disk, minimal mode */
ap_scene *SC;             /* a sleigh scene (n = k = 3: S is not its simulation) */
ap_builder *B;            /* one body, nothing else */
ap_scene_out *O;          /* a run's outputs of SC */
ap_plan *PL;              /* one grid: bodies.sleigh.mass = 1, 1.5, 2 */
ap_batch *BT;             /* a batch of SC's text */
ap_lin *LN;               /* a linearizer of the heavy top (not linearized) */
char SCENE_PATH[4096];
const char SCENE[] =
    "name: api\n"
    "bodies:\n  sleigh: {mass: 1.0, com: [1.0, 0, 0], inertia: [1.0, 1.0, 1.0]}\n"
    "joints:\n  sleigh: {kind: planar}\n"
    "constraints:\n  blade: {kind: knife_edge, body: sleigh, direction: [0, 1, 0]}\n"
    "initial:\n  sleigh: {x: 0, y: 0, heading: 0, vx: 0.1, heading_rate: 0.2}\n"
    "output:\n  channels: [coordinates, energy]\n";

double q[8] = {0, 0, 1, 0, 0, 0}, v[8], w[64], row[64], T, V, E;
const double axis[3] = {0, 0, 1}, qa[4] = {1, 0, 0, 0};
char msg[256];
const double *lam;
ap_model *om;
ap_data *od;
ap_sim *os;
ap_scene *osc;
ap_builder *ob;
ap_method_info mi;
ap_batch *obt;
ap_lin *oln;
ap_lin_eig eg;
ap_lin_sweep sw;
ap_scene_out *oo;
ap_scene_lin sl;
ap_scene_lin_guess lg;
int stat_[4];
char *msgs[4];
const double sweep_p[3] = {0.0, 1.0, 2.0};
ap_body_state bst;
ap_contact_force cf;
ap_crosscheck_report rep;
ap_scene_run run;
ap_sim_stats st;
int id, given[8];

static void all_cases(void) {
  api_cases_low();
  api_cases_high();
  api_cases_io();
  api_cases_ctrl();
}

/* ---- fixtures ------------------------------------------------------------------------------ */

static int fixtures(const char *root) {
  bs_disk dp = bs_disk_default();
  bs_top tp = bs_top_default();
  ap_system_def sd = sysdef(3, 3, 1);
  char m[512] = "";
  BM = bs_disk_model(&dp), TM = bs_top_model(&tp);
  if (!BM || !TM || ap_model_from_system(&sd, &SM, m, sizeof m) != AP_OK) return 0;
  if (ap_data_create(BM, &BD) || ap_data_create(TM, &TD) || ap_data_create(SM, &SD)) return 0;
  if (bs_disk_state(BM, BD, 0.3, 0.25, 0.7, 0.4, 1.2, 7.0, q, v) != AP_OK) return 0;
  SD->basis = AP_BASIS_ORTHONORMAL;   /* no partition needed */
  memcpy(BD->q, q, sizeof(double) * 6), memcpy(BD->v, v, sizeof(double) * 5);
  for (int i = 0; i < 5; i++) given[i] = i >= 2;
  S = bs_start(BM, AP_MODE_MINIMAL, "dopri5", 1e-8, 1e-10, q, v);
  if (!S || ap_builder_create("api", &B) != AP_OK) return 0;
  ap_body_def bd = ap_body_def_default();
  bd.inertia[0] = bd.inertia[4] = bd.inertia[8] = 1.0;
  if (ap_builder_add_body(B, &bd, NULL) != AP_OK) return 0;
  snprintf(SCENE_PATH, sizeof SCENE_PATH, "%s/examples/scenes/chaplygin_sleigh.yaml", root);
  int rc = ap_scene_load_string(SCENE, strlen(SCENE), "api.yaml", NULL, 0, &SC, m, sizeof m);
  if (rc != AP_OK) fprintf(stderr, "fixture scene: %s\n", m);
  if (rc != AP_OK || ap_scene_out_create(SC, &O) != AP_OK || ap_plan_create(&PL) != AP_OK ||
      ap_plan_add_grid(PL, "bodies.sleigh.mass=1:2:3", m, sizeof m) != AP_OK)
    return 0;
  ap_batch_def bdef = ap_batch_def_default();
  rc = ap_batch_create(SCENE, strlen(SCENE), "api.yaml", NULL, 0, &bdef, &BT, m, sizeof m);
  if (rc != AP_OK) {
    fprintf(stderr, "fixture batch: %s\n", m);
    return 0;
  }
  double tq[4], tw[3];
  bs_top_initial(tq, tw);
  ap_lin_create(TM, NULL, 0.0, tq, tw, &LN);   /* a failed setup still gives a linearizer */
  return LN != NULL;
}

/* ---- the functions the headers declare ---------------------------------------------------- */

#define MAXFN 512
static char declared[MAXFN][64];
static int ndeclared = 0;

/* Adds every name declared after an AP_API token in the header text (the identifier before
 * the first '(' of the declaration). */
static void scan_header(const char *text) {
  for (const char *p = strstr(text, "AP_API"); p; p = strstr(p + 6, "AP_API")) {
    const char *line = p;
    while (line > text && line[-1] != '\n') line--;
    if (*line == '#') continue;   /* the macro's own definition */
    const char *par = strchr(p, '(');
    if (!par) break;
    const char *e = par;
    while (e > p && e[-1] == ' ') e--;
    const char *b = e;
    while (b > p && (b[-1] == '_' || (b[-1] >= 'a' && b[-1] <= 'z') ||
                     (b[-1] >= 'A' && b[-1] <= 'Z') || (b[-1] >= '0' && b[-1] <= '9')))
      b--;
    if (e - b > 0 && e - b < 64 && ndeclared < MAXFN) {
      memcpy(declared[ndeclared], b, (size_t)(e - b));
      declared[ndeclared++][e - b] = '\0';
    }
  }
}

static int scan_headers(const char *root) {
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/include/appell", root);
  DIR *dp = opendir(dir);
  if (!dp) return 0;
  struct dirent *de;
  while ((de = readdir(dp))) {
    size_t len = strlen(de->d_name);
    if (len < 3 || strcmp(de->d_name + len - 2, ".h") != 0) continue;
    char path[8192];
    snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
    FILE *f = fopen(path, "rb");
    if (!f) continue;
    static char buf[1 << 20];
    size_t got = fread(buf, 1, sizeof buf - 1, f);
    buf[got] = '\0';
    fclose(f);
    scan_header(buf);
  }
  closedir(dp);
  return ndeclared;
}

static int has_case(const char *fn) {
  for (int i = 0; i < ncase && i < MAXCASE; i++)
    if (strcmp(case_fn[i], fn) == 0) return 1;
  return 0;
}

static int is_declared(const char *fn) {
  for (int i = 0; i < ndeclared; i++)
    if (strcmp(declared[i], fn) == 0) return 1;
  return 0;
}

/* ---- running -------------------------------------------------------------------------------- */

/* 0: as documented, 1: another result, 2: crash (signal, sanitizer report, hang). */
static int run_one(int i) {
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) return 2;
  if (pid == 0) {
    alarm(60);
    pick = i, ncase = 0;
    all_cases();
    _exit(4);   /* not reached */
  }
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return 2;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return 0;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 3) return 1;
  return 2;
}

int main(int argc, char **argv) {
  const char *root = argc > 1 ? argv[1] : ".";
  if (!fixtures(root)) {
    fprintf(stderr, "test_api: cannot make the fixtures\n");
    return 1;
  }
  all_cases();   /* pick = -1: list the cases */
  int failed = 0, counts[3] = {0, 0, 0};
  if (ncase > MAXCASE) {
    fprintf(stderr, "test_api: %d cases, more than MAXCASE = %d\n", ncase, MAXCASE);
    return 1;
  }
  for (int i = 0; i < ncase; i++) {
    int r = run_one(i);
    counts[r]++;
    if (r) printf("  %-6s %s(%s)\n", r == 2 ? "CRASH" : "WRONG", case_fn[i], case_what[i]);
  }
  printf("test_api: %d calls with NULL or out-of-range arguments: %d as documented, %d other "
         "results, %d crashed\n", ncase, counts[0], counts[1], counts[2]);
  failed += counts[1] + counts[2];
  int uncovered = 0;
  if (scan_headers(root) == 0) {
    fprintf(stderr, "test_api: no AP_API declaration found under %s/include/appell\n", root);
    failed++;
  }
  for (int i = 0; i < ndeclared; i++)
    if (!has_case(declared[i])) {
      printf("  MISSING a case for %s (declared AP_API in include/appell/)\n", declared[i]);
      uncovered++;
    }
  for (int i = 0; i < ncase; i++)
    if (!is_declared(case_fn[i]) && (i == 0 || strcmp(case_fn[i], case_fn[i - 1]) != 0)) {
      printf("  STALE case for %s: no longer declared AP_API\n", case_fn[i]);
      uncovered++;
    }
  printf("test_api: %d public functions declared, every one called: %s\n", ndeclared,
         uncovered ? "no" : "yes");
  failed += uncovered;
  if (bs_failures()) failed++;
  ap_scene_out_free(O), ap_plan_free(PL), ap_batch_free(BT), ap_lin_free(LN);
  ap_scene_free(SC), ap_sim_free(S), ap_builder_free(B);
  ap_data_free(BD), ap_data_free(TD), ap_data_free(SD);
  ap_model_free(BM), ap_model_free(TM), ap_model_free(SM);
  printf("test_api: %s\n", failed ? "FAILED" : "passed");
  return failed ? 1 : 0;
}
