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

#include "bodysys.h"

/* ---- the cases ------------------------------------------------------------------------------ */

static int pick = -1;          /* the case a child runs; -1 in the parent (listing) */
static int ncase = 0;
#define MAXCASE 512
static const char *case_fn[MAXCASE], *case_what[MAXCASE];

/* Registers a case; in the child of case `pick`, evaluates it and exits 0 (as documented)
 * or 3 (another result). */
#define CASE(fn, what, ...)                                                              \
  do {                                                                                   \
    if (ncase == pick) _exit((__VA_ARGS__) ? 0 : 3);                                     \
    if (ncase < MAXCASE) case_fn[ncase] = #fn, case_what[ncase] = what;                 \
    ncase++;                                                                             \
  } while (0)

static ap_model *BM, *TM, *SM;   /* rolling disk (body model, b = 2), heavy top, sleigh (math) */
static ap_data *BD, *TD, *SD;    /* their data; TD is the wrong data for BM and SM */
static ap_sim *S;                /* the disk, minimal mode */
static ap_scene *SC;             /* a sleigh scene (n = k = 3: S is not its simulation) */
static ap_builder *B;            /* one body, nothing else */
static ap_scene_out *O;          /* a run's outputs of SC */
static ap_plan *PL;              /* one grid: bodies.sleigh.mass = 1, 1.5, 2 */
static ap_batch *BT;             /* a batch of SC's text */
static ap_lin *LN;               /* a linearizer of the heavy top (not linearized) */
static char SCENE_PATH[4096];
static const char SCENE[] =
    "name: api\n"
    "bodies:\n  sleigh: {mass: 1.0, com: [1.0, 0, 0], inertia: [1.0, 1.0, 1.0]}\n"
    "joints:\n  sleigh: {kind: planar}\n"
    "constraints:\n  blade: {kind: knife_edge, body: sleigh, direction: [0, 1, 0]}\n"
    "initial:\n  sleigh: {x: 0, y: 0, heading: 0, vx: 0.1, heading_rate: 0.2}\n"
    "output:\n  channels: [coordinates, energy]\n";

static double q[8] = {0, 0, 1, 0, 0, 0}, v[8], w[64], row[64], T, V, E;
static const double axis[3] = {0, 0, 1}, qa[4] = {1, 0, 0, 0};
static char msg[256];
static const double *lam;
static ap_model *om;
static ap_data *od;
static ap_sim *os;
static ap_scene *osc;
static ap_builder *ob;
static ap_method_info mi;
static ap_batch *obt;
static ap_lin *oln;
static ap_lin_eig eg;
static ap_lin_sweep sw;
static ap_scene_out *oo;
static ap_scene_lin sl;
static ap_scene_lin_guess lg;
static int stat_[4];
static char *msgs[4];
static const double sweep_p[3] = {0.0, 1.0, 2.0};
static ap_body_state bst;
static ap_contact_force cf;
static ap_crosscheck_report rep;
static ap_scene_run run;
static ap_sim_stats st;
static int id, given[8];

static int is_nan(double x) { return isnan(x); }
static int is_q(const char *s) { return s && strcmp(s, "?") == 0; }
static int is_empty(const char *s) { return s && s[0] == '\0'; }
static int all_zero(const void *p, size_t n) {
  const unsigned char *c = p;
  for (size_t i = 0; i < n; i++)
    if (c[i]) return 0;
  return 1;
}

/* The sleigh's math-level definition (valid with n = k = 3, b = 1, Christoffel bias), with the
 * sizes given. */
static rs_sleigh sleigh_p = {1.0, 1.0, 1.0};
static ap_system_def sysdef(int n, int k, int b) {
  ap_system_def d;
  rs_sleigh_system(&sleigh_p, 0, &d);
  d.n = n, d.k = k, d.b = b;
  return d;
}
/* ap_model_from_system refuses d: AP_ERR_ARG and no model. */
static int refused(ap_system_def d) {
  int rc = ap_model_from_system(&d, &om, msg, sizeof msg);
  return rc == AP_ERR_ARG && om == NULL;
}
static ap_system_def no_metric(void) {
  ap_system_def d = sysdef(3, 3, 1);
  d.metric = NULL;
  return d;
}
static ap_system_def bias_source(int src) {
  ap_system_def d = sysdef(3, 3, 1);
  d.bias_source = (ap_bias_source)src;
  return d;
}
static ap_system_def no_constraint_fn(void) {
  ap_system_def d = sysdef(3, 3, 1);
  d.constraint = NULL;
  return d;
}

static ap_sim_def simdef(void) { return ap_sim_def_default(); }
static int sim_create_def(ap_sim_def d) {
  int rc = ap_sim_create(BM, &d, 0.0, q, v, &os, msg, sizeof msg);
  return rc == AP_ERR_ARG && os == NULL;
}

/* A builder with one body and the element given, compiled: AP_ERR_ARG, no model. */
static int compile_bad(const ap_joint_def *j, const ap_constraint_def *c, const ap_effect_def *e,
                       const ap_body_def *bd) {
  ap_builder *b = NULL;
  ap_body_def d = ap_body_def_default();
  d.inertia[0] = d.inertia[4] = d.inertia[8] = 1.0;
  ap_builder_create("bad", &b);
  ap_builder_add_body(b, bd ? bd : &d, NULL);
  ap_joint_def jd = ap_joint_def_default();
  jd.child = 0;
  ap_builder_add_joint(b, j ? j : &jd, NULL);
  if (c) ap_builder_add_constraint(b, c, NULL);
  if (e) ap_builder_add_effect(b, e, NULL);
  int rc = ap_builder_compile(b, &om);
  return rc == AP_ERR_ARG && om == NULL && ap_builder_message(b)[0] != '\0';
}
static ap_joint_def joint(ap_joint_kind kind, int parent, int child) {
  ap_joint_def j = ap_joint_def_default();
  j.kind = kind, j.parent = parent, j.child = child;
  return j;
}
static ap_constraint_def con(ap_constraint_kind kind, int body) {
  ap_constraint_def c = ap_constraint_def_default();
  c.kind = kind, c.body = body;
  return c;
}
static ap_effect_def eff(ap_effect_kind kind, int body) {
  ap_effect_def e = ap_effect_def_default();
  e.kind = kind, e.body = body;
  return e;
}

static int load_string(const char *text, size_t len, const char *const *sets, int nsets,
                       ap_scene **out, char *m, size_t mlen) {
  return ap_scene_load_string(text, len, "api.yaml", sets, nsets, out, m, mlen);
}
static const char *const no_sets[1] = {NULL};
static const char *const good_sets[1] = {"bodies.sleigh.mass=2"};

static void cases_status_system(void) {
  CASE(ap_strerror, "unknown code", ap_strerror(12345) && ap_strerror(12345)[0]);
  CASE(ap_strerror, "INT_MIN", ap_strerror(INT_MIN) != NULL);
  CASE(ap_system_def_default, "no arguments", ap_system_def_default().n == 0);
  CASE(ap_model_from_system, "def NULL",
       ap_model_from_system(NULL, &om, msg, sizeof msg) == AP_ERR_ARG && !om);
  CASE(ap_model_from_system, "out NULL",
       ap_model_from_system(&(ap_system_def){0}, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_model_from_system, "msg NULL, length > 0",
       ap_model_from_system(NULL, &om, NULL, 100) == AP_ERR_ARG);
  CASE(ap_model_from_system, "n = 0", refused(sysdef(0, 3, 1)));
  CASE(ap_model_from_system, "n = -1", refused(sysdef(-1, 3, 1)));
  CASE(ap_model_from_system, "k = -1", refused(sysdef(3, -1, 1)));
  CASE(ap_model_from_system, "b = -1", refused(sysdef(3, 3, -1)));
  CASE(ap_model_from_system, "n != k without kinematic", refused(sysdef(4, 3, 1)));
  CASE(ap_model_from_system, "metric NULL", refused(no_metric()));
  CASE(ap_model_from_system, "constraint NULL with b = 1", refused(no_constraint_fn()));
  CASE(ap_model_from_system, "bias_source 99", refused(bias_source(99)));
  CASE(ap_model_from_system, "bias_source -1", refused(bias_source(-1)));
  CASE(ap_model_from_system, "n = k = 2^22 (n k^2 overflows)",
       refused(sysdef(1 << 22, 1 << 22, 0)));
  CASE(ap_model_from_system, "n = k = INT_MAX", refused(sysdef(INT_MAX, INT_MAX, 0)));
  CASE(ap_model_from_system, "b = INT_MAX", refused(sysdef(3, 3, INT_MAX)));
  CASE(ap_model_free, "NULL", (ap_model_free(NULL), 1));
  CASE(ap_model_n, "NULL", ap_model_n(NULL) == AP_ERR_ARG);
  CASE(ap_model_k, "NULL", ap_model_k(NULL) == AP_ERR_ARG);
  CASE(ap_model_b, "NULL", ap_model_b(NULL) == AP_ERR_ARG);
  CASE(ap_model_name, "NULL", is_q(ap_model_name(NULL)));
  CASE(ap_model_coord_name, "m NULL", is_q(ap_model_coord_name(NULL, 0)));
  CASE(ap_model_coord_name, "i = -1", is_q(ap_model_coord_name(SM, -1)));
  CASE(ap_model_coord_name, "i = n", is_q(ap_model_coord_name(SM, 3)));
  CASE(ap_model_speed_name, "m NULL", is_q(ap_model_speed_name(NULL, 0)));
  CASE(ap_model_speed_name, "i = k", is_q(ap_model_speed_name(SM, 3)));
  CASE(ap_model_constraint_name, "m NULL", is_q(ap_model_constraint_name(NULL, 0)));
  CASE(ap_model_constraint_name, "s = -1", is_q(ap_model_constraint_name(SM, -1)));
  CASE(ap_model_constraint_name, "s = b", is_q(ap_model_constraint_name(SM, 1)));
  CASE(ap_data_create, "m NULL", ap_data_create(NULL, &od) == AP_ERR_ARG && !od);
  CASE(ap_data_create, "out NULL", ap_data_create(SM, NULL) == AP_ERR_ARG);
  CASE(ap_data_free, "NULL", (ap_data_free(NULL), 1));
}

/* The model-and-data functions of the core: m NULL, d NULL, d made for another model. */
typedef int (*md_fn)(const ap_model *, ap_data *);
#define MD_CASES(fn)                                                                     \
  do {                                                                                   \
    CASE(fn, "m NULL", fn(NULL, SD) == AP_ERR_ARG);                                      \
    CASE(fn, "d NULL", fn(SM, NULL) == AP_ERR_ARG);                                      \
    CASE(fn, "d of another model", fn(SM, TD) == AP_ERR_ARG);                            \
  } while (0)

static void cases_core(void) {
  MD_CASES(ap_partition);
  MD_CASES(ap_fwd_position);
  MD_CASES(ap_fwd_velocity);
  MD_CASES(ap_fwd_acceleration);
  MD_CASES(ap_fwd_reactions);
  MD_CASES(ap_forward);
  CASE(ap_forward, "body model, d of another body model", ap_forward(BM, TD) == AP_ERR_ARG);
  CASE(ap_project_speeds, "m NULL", ap_project_speeds(NULL, SD, v, &T) == AP_ERR_ARG);
  CASE(ap_project_speeds, "d NULL", ap_project_speeds(SM, NULL, v, &T) == AP_ERR_ARG);
  CASE(ap_project_speeds, "v NULL", ap_project_speeds(SM, SD, NULL, &T) == AP_ERR_ARG);
  CASE(ap_project_speeds, "d of another model", ap_project_speeds(SM, TD, v, &T) == AP_ERR_ARG);
  CASE(ap_project_speeds, "change NULL (optional)", ap_project_speeds(SM, SD, v, NULL) == AP_OK);
  CASE(ap_constraint_residual, "d NULL", is_nan(ap_constraint_residual(NULL, v)));
  CASE(ap_constraint_residual, "v NULL", is_nan(ap_constraint_residual(SD, NULL)));
  CASE(ap_kinetic_energy, "d NULL", is_nan(ap_kinetic_energy(NULL, v)));
  CASE(ap_kinetic_energy, "v NULL", is_nan(ap_kinetic_energy(SD, NULL)));
}

static void cases_sim(void) {
  ap_sim_def bad = simdef();
  CASE(ap_sim_def_default, "no arguments", ap_sim_def_default().rtol > 0);
  CASE(ap_sim_create, "out NULL",
       ap_sim_create(BM, &bad, 0, q, v, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_sim_create, "m NULL",
       ap_sim_create(NULL, &bad, 0, q, v, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "def NULL",
       ap_sim_create(BM, NULL, 0, q, v, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "q0 NULL",
       ap_sim_create(BM, &bad, 0, NULL, v, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "v0 NULL",
       ap_sim_create(BM, &bad, 0, q, NULL, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "msg NULL, length > 0",
       ap_sim_create(NULL, &bad, 0, q, v, &os, NULL, 100) == AP_ERR_ARG);
  CASE(ap_sim_create, "t0 NaN",
       ap_sim_create(BM, &bad, NAN, q, v, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "t0 inf",
       ap_sim_create(BM, &bad, INFINITY, q, v, &os, msg, sizeof msg) == AP_ERR_ARG && !os);
  CASE(ap_sim_create, "mode 99", sim_create_def((bad.mode = (ap_mode)99, bad)));
  CASE(ap_sim_create, "mode -1", sim_create_def((bad.mode = (ap_mode)-1, bad)));
  CASE(ap_sim_create, "method NULL", sim_create_def((bad.method = NULL, bad)));
  CASE(ap_sim_create, "method unknown", sim_create_def((bad.method = "nosuch", bad)));
  CASE(ap_sim_create, "rtol -1", sim_create_def((bad.rtol = -1, bad)));
  CASE(ap_sim_create, "atol NaN", sim_create_def((bad.atol = NAN, bad)));
  CASE(ap_sim_create, "rk4 with h_fixed 0",
       sim_create_def((bad.method = "rk4", bad.h_fixed = 0, bad)));
  CASE(ap_sim_create, "max_steps 0", sim_create_def((bad.max_steps = 0, bad)));
  CASE(ap_sim_create, "h_max -1", sim_create_def((bad.h_max = -1, bad)));
  CASE(ap_sim_create, "h_init NaN", sim_create_def((bad.h_init = NAN, bad)));
  CASE(ap_sim_advance, "s NULL", ap_sim_advance(NULL, 1.0) == AP_ERR_ARG);
  CASE(ap_sim_advance, "tout NaN", ap_sim_advance(S, NAN) == AP_ERR_ARG);
  CASE(ap_sim_advance, "tout before t", ap_sim_advance(S, -1.0) == AP_ERR_ARG);
  CASE(ap_sim_advance, "tout inf", ap_sim_advance(S, INFINITY) == AP_ERR_ARG);
  CASE(ap_sim_time, "NULL", is_nan(ap_sim_time(NULL)));
  CASE(ap_sim_q, "NULL", ap_sim_q(NULL) == NULL);
  CASE(ap_sim_v, "NULL", ap_sim_v(NULL) == NULL);
  CASE(ap_sim_data, "NULL", ap_sim_data(NULL) == NULL);
  CASE(ap_sim_reactions, "s NULL", ap_sim_reactions(NULL, &lam) == AP_ERR_ARG);
  CASE(ap_sim_reactions, "lambda NULL (optional)", ap_sim_reactions(S, NULL) == AP_OK);
  CASE(ap_sim_get_stats, "s NULL: zeroed",
       (memset(&st, 1, sizeof st), ap_sim_get_stats(NULL, &st), all_zero(&st, sizeof st)));
  CASE(ap_sim_get_stats, "st NULL", (ap_sim_get_stats(S, NULL), 1));
  CASE(ap_sim_set_poll, "s NULL", (ap_sim_set_poll(NULL, NULL, NULL), 1));
  CASE(ap_sim_set_poll, "poll NULL (removes it)",
       (ap_sim_set_poll(S, NULL, NULL), ap_sim_advance(S, ap_sim_time(S) + 1e-3) == AP_OK));
  CASE(ap_sim_message, "NULL", is_empty(ap_sim_message(NULL)));
  CASE(ap_sim_warning, "NULL", is_empty(ap_sim_warning(NULL)));
  CASE(ap_sim_free, "NULL", (ap_sim_free(NULL), 1));
  bad = simdef();
  CASE(ap_crosscheck, "m NULL",
       ap_crosscheck(NULL, &bad, 0, q, v, 1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "def NULL",
       ap_crosscheck(BM, NULL, 0, q, v, 1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "q0 NULL",
       ap_crosscheck(BM, &bad, 0, NULL, v, 1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "v0 NULL",
       ap_crosscheck(BM, &bad, 0, q, NULL, 1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "rep NULL",
       ap_crosscheck(BM, &bad, 0, q, v, 1, 2, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "msg NULL, length > 0",
       ap_crosscheck(NULL, &bad, 0, q, v, 1, 2, &rep, NULL, 100) == AP_ERR_ARG);
  CASE(ap_crosscheck, "n_out 0",
       ap_crosscheck(BM, &bad, 0, q, v, 1, 0, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "n_out -1",
       ap_crosscheck(BM, &bad, 0, q, v, 1, -1, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "t_end before t0",
       ap_crosscheck(BM, &bad, 0, q, v, -1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "t_end NaN",
       ap_crosscheck(BM, &bad, 0, q, v, NAN, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_crosscheck, "t_end inf",
       ap_crosscheck(BM, &bad, 0, q, v, INFINITY, 2, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_method_count, "no arguments", ap_method_count() > 0);
  CASE(ap_method_get, "i = -1", ap_method_get(-1, &mi) == AP_ERR_ARG);
  CASE(ap_method_get, "i = count", ap_method_get(ap_method_count(), &mi) == AP_ERR_ARG);
  CASE(ap_method_get, "info NULL", ap_method_get(0, NULL) == AP_ERR_ARG);
  CASE(ap_method_find, "name NULL", ap_method_find(NULL, &mi) == AP_ERR_ARG);
  CASE(ap_method_find, "info NULL", ap_method_find("dopri5", NULL) == AP_ERR_ARG);
  CASE(ap_method_find, "unknown name", ap_method_find("nosuch", &mi) == AP_ERR_ARG);
}

static void cases_builder(void) {
  ap_body_def bd = ap_body_def_default();
  ap_joint_def jd = joint(AP_JOINT_FREE, AP_GROUND, 0);
  ap_constraint_def cd_ = con(AP_CON_ROLLING, 0);
  ap_effect_def ed = ap_effect_def_default();
  CASE(ap_body_def_default, "no arguments", ap_body_def_default().mass > 0);
  CASE(ap_joint_def_default, "no arguments", ap_joint_def_default().parent == AP_GROUND);
  CASE(ap_constraint_def_default, "no arguments", ap_constraint_def_default().body == AP_NONE);
  CASE(ap_effect_def_default, "no arguments", ap_effect_def_default().body == AP_NONE);
  CASE(ap_body_def_uniform, "def NULL", ap_body_def_uniform(NULL, 1.0) == AP_ERR_ARG);
  CASE(ap_body_def_uniform, "mass -1", ap_body_def_uniform(&bd, -1.0) == AP_ERR_ARG);
  CASE(ap_body_def_uniform, "mass NaN", ap_body_def_uniform(&bd, NAN) == AP_ERR_ARG);
  CASE(ap_body_def_uniform, "shape kind 99",
       (bd.shape.kind = (ap_shape_kind)99, ap_body_def_uniform(&bd, 1.0) == AP_ERR_ARG));
  CASE(ap_body_def_uniform, "shape kind -1",
       (bd.shape.kind = (ap_shape_kind)-1, ap_body_def_uniform(&bd, 1.0) == AP_ERR_ARG));
  bd = ap_body_def_default();
  CASE(ap_builder_create, "out NULL", ap_builder_create("x", NULL) == AP_ERR_ARG);
  CASE(ap_builder_create, "name NULL (optional)", ap_builder_create(NULL, &ob) == AP_OK && ob);
  CASE(ap_builder_free, "NULL", (ap_builder_free(NULL), 1));
  CASE(ap_builder_add_body, "b NULL", ap_builder_add_body(NULL, &bd, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_body, "def NULL", ap_builder_add_body(B, NULL, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_body, "id NULL (optional)", ap_builder_add_body(B, &bd, NULL) == AP_OK);
  CASE(ap_builder_add_joint, "b NULL", ap_builder_add_joint(NULL, &jd, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_joint, "def NULL", ap_builder_add_joint(B, NULL, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_joint, "id NULL (optional)", ap_builder_add_joint(B, &jd, NULL) == AP_OK);
  CASE(ap_builder_add_constraint, "b NULL",
       ap_builder_add_constraint(NULL, &cd_, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_constraint, "def NULL",
       ap_builder_add_constraint(B, NULL, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_constraint, "id NULL (optional)",
       ap_builder_add_constraint(B, &cd_, NULL) == AP_OK);
  CASE(ap_builder_add_effect, "b NULL", ap_builder_add_effect(NULL, &ed, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_effect, "def NULL", ap_builder_add_effect(B, NULL, &id) == AP_ERR_ARG);
  CASE(ap_builder_add_effect, "id NULL (optional)", ap_builder_add_effect(B, &ed, NULL) == AP_OK);
  CASE(ap_builder_message, "NULL", is_empty(ap_builder_message(NULL)));
  CASE(ap_builder_compile, "b NULL", ap_builder_compile(NULL, &om) == AP_ERR_ARG && !om);
  CASE(ap_builder_compile, "out NULL", ap_builder_compile(B, NULL) == AP_ERR_ARG);
  ap_joint_def j;
  ap_constraint_def c;
  ap_effect_def e;
  CASE(ap_builder_compile, "joint child 99",
       (j = joint(AP_JOINT_FREE, AP_GROUND, 99), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint child -5",
       (j = joint(AP_JOINT_FREE, AP_GROUND, -5), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint parent 99",
       (j = joint(AP_JOINT_FREE, 99, 0), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint parent -5",
       (j = joint(AP_JOINT_FREE, -5, 0), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint kind 99",
       (j = joint((ap_joint_kind)99, AP_GROUND, 0), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint kind -1",
       (j = joint((ap_joint_kind)-1, AP_GROUND, 0), compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "joint axis zero",
       (j = joint(AP_JOINT_REVOLUTE, AP_GROUND, 0), j.axis[2] = 0,
        compile_bad(&j, NULL, NULL, NULL)));
  CASE(ap_builder_compile, "shape kind 99",
       (bd.shape.kind = (ap_shape_kind)99, compile_bad(NULL, NULL, NULL, &bd)));
  bd = ap_body_def_default();
  CASE(ap_builder_compile, "constraint kind 99",
       (c = con((ap_constraint_kind)99, 0), compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "constraint kind -1",
       (c = con((ap_constraint_kind)-1, 0), compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "rolling body 99",
       (c = con(AP_CON_ROLLING, 99), compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "rolling body -5",
       (c = con(AP_CON_ROLLING, -5), compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "knife edge body 99",
       (c = con(AP_CON_KNIFE_EDGE, 99), compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "ground kind 99",
       (c = con(AP_CON_KNIFE_EDGE, 0), c.ground.kind = (ap_ground_kind)99,
        compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "prescribed speed joint 99",
       (c = con(AP_CON_PRESCRIBED_SPEED, 0), c.joint = 99, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "prescribed speed index 99",
       (c = con(AP_CON_PRESCRIBED_SPEED, 0), c.joint = 0, c.speed = 99,
        compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "prescribed speed index -1",
       (c = con(AP_CON_PRESCRIBED_SPEED, 0), c.joint = 0, c.speed = -1,
        compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "user rows -1",
       (c = con(AP_CON_USER, 0), c.rows = -1, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "user rows 1, no callbacks",
       (c = con(AP_CON_USER, 0), c.rows = 1, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "coincident body2 99",
       (c = con(AP_CON_COINCIDENT, 0), c.body2 = 99, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "coincident axes 0",
       (c = con(AP_CON_COINCIDENT, 0), c.axes = 0, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "point on line, direction 0",
       (c = con(AP_CON_POINT_ON_LINE, 0), c.direction[1] = 0, compile_bad(NULL, &c, NULL, NULL)));
  CASE(ap_builder_compile, "effect kind 99",
       (e = eff((ap_effect_kind)99, 0), compile_bad(NULL, NULL, &e, NULL)));
  CASE(ap_builder_compile, "effect kind -1",
       (e = eff((ap_effect_kind)-1, 0), compile_bad(NULL, NULL, &e, NULL)));
  CASE(ap_builder_compile, "applied body 99",
       (e = eff(AP_EFFECT_APPLIED, 99), compile_bad(NULL, NULL, &e, NULL)));
  CASE(ap_builder_compile, "spring body2 99",
       (e = eff(AP_EFFECT_SPRING, 0), e.body2 = 99, compile_bad(NULL, NULL, &e, NULL)));
  CASE(ap_builder_compile, "joint damping joint 99",
       (e = eff(AP_EFFECT_JOINT_DAMPING, 0), e.joint = 99, compile_bad(NULL, NULL, &e, NULL)));
  CASE(ap_builder_compile, "user effect, no callback",
       (e = eff(AP_EFFECT_USER, 0), compile_bad(NULL, NULL, &e, NULL)));
}

static void cases_body_queries(void) {
  CASE(ap_model_is_body_model, "NULL", ap_model_is_body_model(NULL) == 0);
  CASE(ap_model_body_count, "NULL", ap_model_body_count(NULL) == AP_ERR_ARG);
  CASE(ap_model_body_count, "math-level model", ap_model_body_count(SM) == AP_ERR_ARG);
  CASE(ap_model_find_body, "m NULL", ap_model_find_body(NULL, "disk") == -1);
  CASE(ap_model_find_body, "name NULL", ap_model_find_body(BM, NULL) == -1);
  CASE(ap_model_find_coord, "m NULL", ap_model_find_coord(NULL, "x") == -1);
  CASE(ap_model_find_coord, "name NULL", ap_model_find_coord(BM, NULL) == -1);
  CASE(ap_model_find_speed, "m NULL", ap_model_find_speed(NULL, "x") == -1);
  CASE(ap_model_find_speed, "name NULL", ap_model_find_speed(BM, NULL) == -1);
  CASE(ap_joint_coord_index, "m NULL", ap_joint_coord_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "joint -1", ap_joint_coord_index(BM, -1) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "joint 99", ap_joint_coord_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "math-level model", ap_joint_coord_index(SM, 0) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "m NULL", ap_joint_speed_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "joint 99", ap_joint_speed_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "math-level model", ap_joint_speed_index(SM, 0) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "m NULL", ap_constraint_row_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "constraint -1", ap_constraint_row_index(BM, -1) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "constraint 99", ap_constraint_row_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_body_eval, "m NULL", ap_body_eval(NULL, BD) == AP_ERR_ARG);
  CASE(ap_body_eval, "d NULL", ap_body_eval(BM, NULL) == AP_ERR_ARG);
  CASE(ap_body_eval, "math-level model", ap_body_eval(SM, SD) == AP_ERR_ARG);
  CASE(ap_body_eval, "d of another model", ap_body_eval(BM, TD) == AP_ERR_ARG);
  CASE(ap_body_get_state, "m NULL", ap_body_get_state(NULL, BD, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "d NULL", ap_body_get_state(BM, NULL, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "body -1", ap_body_get_state(BM, BD, -1, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "body 99", ap_body_get_state(BM, BD, 99, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "out NULL", ap_body_get_state(BM, BD, 0, NULL) == AP_ERR_ARG);
  CASE(ap_body_get_state, "d of another model", ap_body_get_state(BM, TD, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "m NULL",
       ap_body_point_jacobian(NULL, BD, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "d NULL",
       ap_body_point_jacobian(BM, NULL, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "body -1",
       ap_body_point_jacobian(BM, BD, -1, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "body 99",
       ap_body_point_jacobian(BM, BD, 99, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "p NULL",
       ap_body_point_jacobian(BM, BD, 0, NULL, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "outputs NULL (optional)",
       ap_body_point_jacobian(BM, BD, 0, axis, NULL, NULL, NULL, NULL, NULL, NULL) == AP_OK);
  CASE(ap_body_point_jacobian, "d of another model",
       ap_body_point_jacobian(BM, TD, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_energy, "m NULL", ap_body_energy(NULL, BD, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_energy, "d NULL", ap_body_energy(BM, NULL, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_energy, "outputs NULL (optional)", ap_body_energy(BM, BD, NULL, NULL) == AP_OK);
  CASE(ap_body_energy, "d of another model", ap_body_energy(BM, TD, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_effect_count, "m NULL", ap_body_effect_count(NULL, BD, 0) == -1);
  CASE(ap_body_effect_count, "d NULL", ap_body_effect_count(BM, NULL, 0) == -1);
  CASE(ap_body_effect_count, "effect -1", ap_body_effect_count(BM, BD, -1) == -1);
  CASE(ap_body_effect_count, "effect 99", ap_body_effect_count(BM, BD, 99) == -1);
  CASE(ap_body_effect_count, "d of another model", ap_body_effect_count(BM, TD, 0) == -1);
  CASE(ap_body_project_q, "m NULL", ap_body_project_q(NULL, BD, q, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "d NULL", ap_body_project_q(BM, NULL, q, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "q NULL", ap_body_project_q(BM, BD, NULL, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "change NULL (optional)", ap_body_project_q(BM, BD, q, NULL) == AP_OK);
  CASE(ap_body_project_q, "d of another model", ap_body_project_q(BM, TD, q, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "m NULL", ap_body_loop_residual(NULL, BD, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "d NULL", ap_body_loop_residual(BM, NULL, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "phi_max NULL", ap_body_loop_residual(BM, BD, NULL) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "d of another model",
       ap_body_loop_residual(BM, TD, &T) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "m NULL",
       ap_body_complete_speeds(NULL, BD, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "d NULL",
       ap_body_complete_speeds(BM, NULL, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "q NULL",
       ap_body_complete_speeds(BM, BD, NULL, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "given NULL",
       ap_body_complete_speeds(BM, BD, q, NULL, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "v NULL",
       ap_body_complete_speeds(BM, BD, q, given, NULL) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "d of another model",
       ap_body_complete_speeds(BM, TD, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "m NULL",
       ap_body_contact_force(NULL, BD, NULL, 0, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "d NULL",
       ap_body_contact_force(BM, NULL, NULL, 0, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "constraint -1",
       ap_body_contact_force(BM, BD, NULL, -1, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "constraint 99",
       ap_body_contact_force(BM, BD, NULL, 99, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "out NULL",
       ap_body_contact_force(BM, BD, NULL, 0, NULL) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "d of another model",
       ap_body_contact_force(BM, TD, NULL, 0, &cf) == AP_ERR_ARG);
  double out[9] = {0};
  CASE(ap_quat_from_axis_angle, "axis NULL: q untouched",
       (ap_quat_from_axis_angle(NULL, 1.0, out), all_zero(out, sizeof out)));
  CASE(ap_quat_from_axis_angle, "q NULL", (ap_quat_from_axis_angle(axis, 1.0, NULL), 1));
  CASE(ap_quat_mul, "a NULL: out untouched",
       (ap_quat_mul(NULL, qa, out), all_zero(out, sizeof out)));
  CASE(ap_quat_mul, "b NULL: out untouched",
       (ap_quat_mul(qa, NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_mul, "out NULL", (ap_quat_mul(qa, qa, NULL), 1));
  CASE(ap_quat_to_matrix, "q NULL: R untouched",
       (ap_quat_to_matrix(NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_to_matrix, "R NULL", (ap_quat_to_matrix(qa, NULL), 1));
  CASE(ap_quat_from_matrix, "R NULL: q untouched",
       (ap_quat_from_matrix(NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_from_matrix, "q NULL", (ap_quat_from_matrix(out, NULL), 1));
}

static void cases_scene(void) {
  size_t n = strlen(SCENE);
  CASE(ap_scene_load, "path NULL",
       ap_scene_load(NULL, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "out NULL",
       ap_scene_load(SCENE_PATH, NULL, 0, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_load, "sets NULL, nsets 1",
       ap_scene_load(SCENE_PATH, NULL, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "nsets -1",
       ap_scene_load(SCENE_PATH, good_sets, -1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "sets[0] NULL",
       ap_scene_load(SCENE_PATH, no_sets, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "msg NULL, length > 0",
       ap_scene_load(NULL, NULL, 0, &osc, NULL, 100) == AP_ERR_ARG);
  CASE(ap_scene_load, "path is a directory",
       ap_scene_load("/", NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "sets NULL, nsets 0 (no overrides)",
       ap_scene_load(SCENE_PATH, NULL, 0, &osc, msg, sizeof msg) == AP_OK);
  CASE(ap_scene_load_string, "text NULL",
       load_string(NULL, 10, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "out NULL",
       load_string(SCENE, n, NULL, 0, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "sets NULL, nsets 1",
       load_string(SCENE, n, NULL, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "nsets -1",
       load_string(SCENE, n, good_sets, -1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "sets[0] NULL",
       load_string(SCENE, n, no_sets, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "msg NULL, length > 0",
       load_string(NULL, 10, NULL, 0, &osc, NULL, 100) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "msg_len 0",
       load_string(SCENE, n, no_sets, 1, &osc, msg, 0) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "name NULL (optional)",
       ap_scene_load_string(SCENE, n, NULL, NULL, 0, &osc, msg, sizeof msg) == AP_OK);
  CASE(ap_scene_load_string, "length 0",
       load_string(SCENE, 0, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_free, "NULL", (ap_scene_free(NULL), 1));
  CASE(ap_scene_model, "NULL", ap_scene_model(NULL) == NULL);
  CASE(ap_scene_get_run, "s NULL: zeroed",
       (memset(&run, 1, sizeof run), ap_scene_get_run(NULL, &run), all_zero(&run, sizeof run)));
  CASE(ap_scene_get_run, "run NULL", (ap_scene_get_run(SC, NULL), 1));
  CASE(ap_scene_initial_state, "s NULL",
       ap_scene_initial_state(NULL, q, v, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "q0 NULL",
       ap_scene_initial_state(SC, NULL, v, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "v0 NULL",
       ap_scene_initial_state(SC, q, NULL, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "report, msg NULL (optional)",
       ap_scene_initial_state(SC, q, v, NULL, 100, NULL, 100) == AP_OK);
  CASE(ap_scene_check_time, "s NULL",
       ap_scene_check_time(NULL, 0.0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_check_time, "msg NULL, length > 0 (optional)",
       ap_scene_check_time(SC, 0.0, NULL, 100) == AP_OK);
  CASE(ap_scene_output_count, "NULL", ap_scene_output_count(NULL) == 0);
  CASE(ap_scene_output_name, "s NULL", ap_scene_output_name(NULL, 0) == NULL);
  CASE(ap_scene_output_name, "i -1", ap_scene_output_name(SC, -1) == NULL);
  CASE(ap_scene_output_name, "i = count",
       ap_scene_output_name(SC, ap_scene_output_count(SC)) == NULL);
  CASE(ap_scene_output_row, "s NULL", ap_scene_output_row(NULL, S, row) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "sim NULL", ap_scene_output_row(SC, NULL, row) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "row NULL", ap_scene_output_row(SC, S, NULL) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "sim of another model", ap_scene_output_row(SC, S, row) == AP_ERR_ARG);
  CASE(ap_scene_energy, "s NULL", ap_scene_energy(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "q NULL", ap_scene_energy(SC, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "v NULL", ap_scene_energy(SC, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "E NULL", ap_scene_energy(SC, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_residual, "s NULL", ap_scene_residual(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "q NULL", ap_scene_residual(SC, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "v NULL", ap_scene_residual(SC, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "resid NULL", ap_scene_residual(SC, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_conserves_energy, "NULL", ap_scene_conserves_energy(NULL) == 0);
  CASE(ap_scene_count, "s NULL", ap_scene_count(NULL, AP_SCENE_BODIES) == 0);
  CASE(ap_scene_count, "section 99", ap_scene_count(SC, (ap_scene_section)99) == 0);
  CASE(ap_scene_count, "section -1", ap_scene_count(SC, (ap_scene_section)-1) == 0);
  CASE(ap_scene_element_name, "s NULL", ap_scene_element_name(NULL, AP_SCENE_BODIES, 0) == NULL);
  CASE(ap_scene_element_name, "section 99",
       ap_scene_element_name(SC, (ap_scene_section)99, 0) == NULL);
  CASE(ap_scene_element_name, "i -1", ap_scene_element_name(SC, AP_SCENE_BODIES, -1) == NULL);
  CASE(ap_scene_element_name, "i 99", ap_scene_element_name(SC, AP_SCENE_CHANNELS, 99) == NULL);
  CASE(ap_scene_element_kind, "s NULL", ap_scene_element_kind(NULL, AP_SCENE_BODIES, 0) == NULL);
  CASE(ap_scene_element_kind, "section 99",
       ap_scene_element_kind(SC, (ap_scene_section)99, 0) == NULL);
  CASE(ap_scene_element_kind, "i -1", ap_scene_element_kind(SC, AP_SCENE_EFFECTS, -1) == NULL);
  CASE(ap_scene_element_kind, "i 99", ap_scene_element_kind(SC, AP_SCENE_CONSTRAINTS, 99) == NULL);
  CASE(ap_scene_name, "NULL", ap_scene_name(NULL) == NULL);
}

static int eig_fn(double p_, int n, double *re, double *im, void *user) {
  (void)user;
  for (int i = 0; i < n; i++) re[i] = p_ - 1.0 - i, im[i] = 0.0;
  return 0;
}

static void cases_scene_runs(void) {
  CASE(ap_scene_out_create, "s NULL", ap_scene_out_create(NULL, &oo) == AP_ERR_ARG && !oo);
  CASE(ap_scene_out_create, "out NULL", ap_scene_out_create(SC, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "o NULL", ap_scene_out_row(NULL, S, row) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "sim NULL", ap_scene_out_row(O, NULL, row) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "row NULL", ap_scene_out_row(O, S, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "sim of another model", ap_scene_out_row(O, S, row) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "o NULL", ap_scene_out_energy(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "q NULL", ap_scene_out_energy(O, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "v NULL", ap_scene_out_energy(O, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "E NULL", ap_scene_out_energy(O, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_free, "NULL", (ap_scene_out_free(NULL), 1));
  CASE(ap_scene_constant, "text NULL", ap_scene_constant(NULL, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_constant, "x NULL", ap_scene_constant("2", NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_constant, "not an expression",
       ap_scene_constant("1 +", &E, msg, sizeof msg) == AP_ERR_ARG && msg[0]);
  CASE(ap_scene_constant, "msg NULL, length > 0 (optional)",
       ap_scene_constant("70*deg", &E, NULL, 100) == AP_OK);
  CASE(ap_scene_get_linearize, "s NULL",
       ap_scene_get_linearize(NULL, &sl, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_get_linearize, "out NULL",
       ap_scene_get_linearize(SC, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_lin_free, "NULL", (ap_scene_lin_free(NULL), 1));
  CASE(ap_scene_lin_guess_load, "path NULL",
       ap_scene_lin_guess_load(NULL, NULL, 0, NULL, 0, &lg, msg, sizeof msg) == AP_ERR_ARG &&
           msg[0] && !lg.scene);
  CASE(ap_scene_lin_guess_load, "out NULL",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, 0, NULL, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_scene_lin_guess_load, "nsets -1",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, -1, &lg, msg, sizeof msg) ==
           AP_ERR_ARG && !lg.scene);
  CASE(ap_scene_lin_guess_load, "sets NULL, nsets 1",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, 1, &lg, msg, sizeof msg) ==
           AP_ERR_ARG && !lg.scene);
  CASE(ap_scene_lin_guess_load, "a missing file",
       ap_scene_lin_guess_load("/nonexistent/x.yaml", NULL, 0, NULL, 0, &lg, msg, sizeof msg) !=
           AP_OK && msg[0] && !lg.scene && !lg.q);
  CASE(ap_scene_lin_guess_load, "msg NULL (optional)",
       ap_scene_lin_guess_load(NULL, NULL, 0, NULL, 0, &lg, NULL, 0) == AP_ERR_ARG);
  CASE(ap_scene_lin_guess_free, "NULL", (ap_scene_lin_guess_free(NULL), 1));
  CASE(ap_scene_lin_guess_free, "zeroed", (ap_scene_lin_guess_free(&lg), isnan(lg.speed)));
  CASE(ap_scene_lin_def, "NULL: the defaults",
       ap_scene_lin_def(NULL).about == AP_LIN_STEADY && !ap_scene_lin_def(NULL).speed_dir);
  CASE(ap_scene_lin_create, "g NULL", ap_scene_lin_create(NULL, NULL, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_scene_lin_create, "g without a scene",
       ap_scene_lin_create(&lg, NULL, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_scene_lin_create, "out NULL", ap_scene_lin_create(&lg, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "m NULL",
       ap_body_actuator_partials(NULL, BD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "d NULL",
       ap_body_actuator_partials(BM, NULL, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "d of another model",
       ap_body_actuator_partials(BM, TD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "effect -1",
       ap_body_actuator_partials(BM, BD, -1, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "effect 99",
       ap_body_actuator_partials(BM, BD, 99, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "gravity, not an actuator",
       ap_body_actuator_partials(BM, BD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
}

static void cases_batch(void) {
  double vals[64];
  const char *const one[1] = {"bodies.sleigh.mass=2"};
  size_t n = strlen(SCENE);
  ap_batch_def bd = ap_batch_def_default();
  CASE(ap_plan_create, "out NULL", ap_plan_create(NULL) == AP_ERR_ARG);
  CASE(ap_plan_free, "NULL", (ap_plan_free(NULL), 1));
  CASE(ap_plan_add_grid, "p NULL",
       ap_plan_add_grid(NULL, "a=1:2:3", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "spec NULL", ap_plan_add_grid(PL, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "spec without '='",
       ap_plan_add_grid(PL, "nonsense", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "msg NULL, length > 0",
       ap_plan_add_grid(PL, "x", NULL, 100) == AP_ERR_ARG);
  CASE(ap_plan_add_random, "p NULL",
       ap_plan_add_random(NULL, "a=uniform(0,1)", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_random, "spec NULL",
       ap_plan_add_random(PL, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "p NULL", ap_plan_set_samples(NULL, 4, 1) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "samples 0", ap_plan_set_samples(PL, 0, 1) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "samples -5", ap_plan_set_samples(PL, -5, 1) == AP_ERR_ARG);
  CASE(ap_plan_count, "NULL", ap_plan_count(NULL) == 0);
  CASE(ap_plan_nparams, "NULL", ap_plan_nparams(NULL) == 0);
  CASE(ap_plan_path, "p NULL", ap_plan_path(NULL, 0) == NULL);
  CASE(ap_plan_path, "r -1", ap_plan_path(PL, -1) == NULL);
  CASE(ap_plan_path, "r 99", ap_plan_path(PL, 99) == NULL);
  CASE(ap_plan_value, "p NULL", ap_plan_value(NULL, 0, 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "i -1", ap_plan_value(PL, -1, 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "i = count",
       ap_plan_value(PL, ap_plan_count(PL), 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "r 5", ap_plan_value(PL, 0, 5, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "buf too short", ap_plan_value(PL, 0, 0, &E, msg, 3) == AP_ERR_ARG);
  CASE(ap_plan_value, "x, buf NULL (optional)", ap_plan_value(PL, 0, 0, NULL, NULL, 0) == AP_OK);
  CASE(ap_plan_typical, "p NULL", ap_plan_typical(NULL, 0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_typical, "r 5", ap_plan_typical(PL, 5, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_typical, "buf NULL", ap_plan_typical(PL, 0, NULL, 10) == AP_ERR_ARG);
  CASE(ap_batch_def_default, "no arguments", ap_batch_def_default().threads >= 1);
  CASE(ap_batch_create, "text NULL",
       ap_batch_create(NULL, 9, "b", NULL, 0, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "out NULL",
       ap_batch_create(SCENE, n, "b", NULL, 0, &bd, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_create, "sets NULL, nsets 1",
       ap_batch_create(SCENE, n, "b", NULL, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "nsets -1",
       ap_batch_create(SCENE, n, "b", one, -1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "sets[0] NULL",
       ap_batch_create(SCENE, n, "b", no_sets, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG &&
           !obt);
  CASE(ap_batch_load, "path NULL",
       ap_batch_load(NULL, NULL, 0, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_load, "sets NULL, nsets 1",
       ap_batch_load(SCENE_PATH, NULL, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_load, "out NULL",
       ap_batch_load(SCENE_PATH, NULL, 0, &bd, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_free, "NULL", (ap_batch_free(NULL), 1));
  CASE(ap_batch_ncols, "NULL", ap_batch_ncols(NULL) == 0);
  CASE(ap_batch_col_name, "b NULL", ap_batch_col_name(NULL, 0) == NULL);
  CASE(ap_batch_col_name, "j -1", ap_batch_col_name(BT, -1) == NULL);
  CASE(ap_batch_col_name, "j = ncols", ap_batch_col_name(BT, ap_batch_ncols(BT)) == NULL);
  CASE(ap_batch_check, "b NULL", ap_batch_check(NULL, one, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "sets NULL, nsets 1",
       ap_batch_check(BT, NULL, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "nsets -1", ap_batch_check(BT, one, -1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "sets[0] NULL",
       ap_batch_check(BT, no_sets, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check_plan, "b NULL", ap_batch_check_plan(NULL, PL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check_plan, "p NULL", ap_batch_check_plan(BT, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_run, "b NULL", ap_batch_run(NULL, 1, 1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "count -1", ap_batch_run(BT, -1, 1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "nper -1", ap_batch_run(BT, 1, -1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "sets NULL", ap_batch_run(BT, 1, 1, NULL, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "values NULL", ap_batch_run(BT, 1, 1, one, NULL, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "status NULL", ap_batch_run(BT, 1, 1, one, vals, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "sets[0] NULL", ap_batch_run(BT, 1, 1, no_sets, vals, stat_, msgs) == AP_OK &&
       stat_[0] == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "b NULL",
       ap_batch_run_plan(NULL, PL, 0, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "p NULL",
       ap_batch_run_plan(BT, NULL, 0, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "first -1",
       ap_batch_run_plan(BT, PL, -1, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "past the plan",
       ap_batch_run_plan(BT, PL, 2, 5, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "values NULL",
       ap_batch_run_plan(BT, PL, 0, 1, NULL, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_messages_free, "messages NULL", (ap_batch_messages_free(3, NULL), 1));
  CASE(ap_batch_messages_free, "count -1", (ap_batch_messages_free(-1, msgs), 1));
}

static void cases_lin(void) {
  double tq[4], tw[3], sv[2] = {0.0, 1.0};
  int sel[1] = {0};
  bs_top_initial(tq, tw);
  CASE(ap_lin_def_default, "no arguments", ap_lin_def_default().about == AP_LIN_STEADY);
  CASE(ap_lin_create, "m NULL", ap_lin_create(NULL, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "q NULL", ap_lin_create(TM, NULL, 0.0, NULL, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "t NaN", ap_lin_create(TM, NULL, NAN, tq, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "out NULL", ap_lin_create(TM, NULL, 0.0, tq, tw, NULL) == AP_ERR_ARG);
  CASE(ap_lin_create, "q NaN (a message in the linearizer)",
       (tq[1] = NAN, ap_lin_create(TM, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && oln &&
                         strstr(ap_lin_message(oln), "nan")));
  CASE(ap_lin_create, "v Inf (a message in the linearizer)",
       (tw[0] = INFINITY, ap_lin_create(TM, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && oln &&
                              strstr(ap_lin_message(oln), "inf")));
  CASE(ap_lin_create, "def, v NULL (defaults, zero speeds)",
       (ap_lin_create(TM, NULL, 0.0, tq, NULL, &oln), oln != NULL));
  CASE(ap_lin_free, "NULL", (ap_lin_free(NULL), 1));
  CASE(ap_lin_message, "NULL: a fixed text", ap_lin_message(NULL) && ap_lin_message(NULL)[0]);
  CASE(ap_lin_operating_point, "L NULL", ap_lin_operating_point(NULL, 0.0) == AP_ERR_ARG);
  CASE(ap_lin_operating_point, "s Inf", ap_lin_operating_point(LN, INFINITY) == AP_ERR_ARG);
  CASE(ap_lin_q, "NULL", ap_lin_q(NULL) == NULL);
  CASE(ap_lin_v, "NULL", ap_lin_v(NULL) == NULL);
  CASE(ap_lin_linearize, "NULL", ap_lin_linearize(NULL) == AP_ERR_ARG);
  CASE(ap_lin_nx, "NULL", ap_lin_nx(NULL) == 0);
  CASE(ap_lin_nu, "NULL", ap_lin_nu(NULL) == 0);
  CASE(ap_lin_state_name, "L NULL", ap_lin_state_name(NULL, 0) == NULL);
  CASE(ap_lin_state_name, "i -1", ap_lin_state_name(LN, -1) == NULL);
  CASE(ap_lin_state_name, "i 999", ap_lin_state_name(LN, 999) == NULL);
  CASE(ap_lin_input_name, "L NULL", ap_lin_input_name(NULL, 0) == NULL);
  CASE(ap_lin_input_name, "j 999", ap_lin_input_name(LN, 999) == NULL);
  CASE(ap_lin_is_cyclic, "L NULL", ap_lin_is_cyclic(NULL, 0) == 0);
  CASE(ap_lin_is_cyclic, "i 999", ap_lin_is_cyclic(LN, 999) == 0);
  CASE(ap_lin_find_state, "L NULL", ap_lin_find_state(NULL, "x") == -1);
  CASE(ap_lin_find_state, "name NULL", ap_lin_find_state(LN, NULL) == -1);
  CASE(ap_lin_A, "NULL", ap_lin_A(NULL) == NULL);
  CASE(ap_lin_A_error, "NULL", ap_lin_A_error(NULL) == NULL);
  CASE(ap_lin_B, "NULL", ap_lin_B(NULL) == NULL);
  CASE(ap_lin_rates, "NULL", ap_lin_rates(NULL) == NULL);
  CASE(ap_lin_method_used, "NULL", ap_lin_method_used(NULL) == AP_LIN_AUTO);
  CASE(ap_lin_fallback, "NULL", ap_lin_fallback(NULL) && !ap_lin_fallback(NULL)[0]);
  CASE(ap_lin_eigen, "L NULL", ap_lin_eigen(NULL, sel, 1, 0) == AP_ERR_ARG);
  CASE(ap_lin_eigen, "not linearized", ap_lin_eigen(LN, sel, 1, 0) == AP_ERR_ARG);
  CASE(ap_lin_get_eigen, "L NULL", ap_lin_get_eigen(NULL, &eg) == AP_ERR_ARG);
  CASE(ap_lin_get_eigen, "out NULL", ap_lin_get_eigen(LN, NULL) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "fn NULL",
       ap_lin_sweep_run(NULL, NULL, 2, sweep_p, 3, 1e-6, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "n 0",
       ap_lin_sweep_run(eig_fn, NULL, 0, sweep_p, 3, 1e-6, 0.0, &sw, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "p NULL",
       ap_lin_sweep_run(eig_fn, NULL, 2, NULL, 3, 1e-6, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "count 0",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 0, 1e-6, 0.0, &sw, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "ptol NaN",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 3, NAN, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "out NULL",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 3, 1e-6, 0.0, NULL, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_free, "NULL", (ap_lin_sweep_free(NULL), 1));
  CASE(ap_lin_sweep_speed, "L NULL",
       ap_lin_sweep_speed(NULL, sv, 2, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "s NULL",
       ap_lin_sweep_speed(LN, NULL, 2, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "count 0",
       ap_lin_sweep_speed(LN, sv, 0, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "out NULL",
       ap_lin_sweep_speed(LN, sv, 2, NULL, 0, 0, 1e-6, NULL) == AP_ERR_ARG);
}

static void all_cases(void) {
  cases_status_system();
  cases_core();
  cases_sim();
  cases_builder();
  cases_body_queries();
  cases_scene();
  cases_scene_runs();
  cases_batch();
  cases_lin();
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
