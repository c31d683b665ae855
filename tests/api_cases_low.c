/* test_api's cases, first half (api_case.h): status codes and math-level systems, the core's
 * stages, simulations, the builder. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_case.h"

static int is_nan(double x) { return isnan(x); }
static int is_q(const char *s) { return s && strcmp(s, "?") == 0; }
static int is_empty(const char *s) { return s && s[0] == '\0'; }

/* The sleigh's math-level definition (valid with n = k = 3, b = 1, Christoffel bias), with the
 * sizes given. */
static rs_sleigh sleigh_p = {1.0, 1.0, 1.0};
ap_system_def sysdef(int n, int k, int b) {
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

/* ap_model_from_system refuses d with a message containing `what`. */
static int refused_with(ap_system_def d, const char *what) {
  return refused(d) && strstr(msg, what) != NULL;
}
/* A valid system with n = k (no constraint rows, h = 0 or the Christoffel bias): accepted. */
static int accepted(int nk, ap_bias_source src) {
  ap_system_def d = sysdef(nk, nk, 0);
  d.bias_source = src;
  d.coord_names = d.speed_names = d.constraint_names = NULL;   /* the sleigh's are 3 */
  int rc = ap_model_from_system(&d, &om, msg, sizeof msg);
  int ok = rc == AP_OK && om && ap_model_k(om) == nk;
  ap_model_free(om), om = NULL;
  return ok;
}
/* An event function valid in every state: t - 1. */
static int time_event(double t, const double *q, const double *v, const ap_data *d, void *user,
                      double *value) {
  (void)q, (void)v, (void)d, (void)user;
  *value = t - 1.0;
  return 0;
}

static ap_system_def unchecked_sys(void) {   /* every field valid but internal_check */
  ap_system_def d = sysdef(3, 3, 1);
  d.internal_check = 0;
  return d;
}
/* A system whose name is longer than a model's name buffer: the name ends in "...". */
static int long_name_cut(void) {
  static const char nm[] = "a_system_name_that_is_much_longer_than_the_sixty_three_bytes_a_model"
                           "_keeps_for_its_name";
  ap_system_def d = sysdef(3, 3, 1);
  d.name = nm;
  int rc = ap_model_from_system(&d, &om, msg, sizeof msg);
  const char *got = rc == AP_OK ? ap_model_name(om) : "";
  size_t len = strlen(got);
  int ok = len == 63 && strcmp(got + len - 3, "...") == 0 && strncmp(got, nm, 60) == 0;
  ap_model_free(om), om = NULL;
  return ok;
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

/* A builder whose name is longer than a model's name buffer: the compiled model's name is cut
 * to 63 bytes ending in "...". */
static int long_builder_name(void) {
  static const char nm[] = "a_model_name_that_is_much_longer_than_the_sixty_three_bytes_a_model_"
                           "keeps_for_its_name";
  ap_builder *b = NULL;
  ap_body_def d = ap_body_def_default();
  d.inertia[0] = d.inertia[4] = d.inertia[8] = 1.0;
  ap_joint_def j = joint(AP_JOINT_REVOLUTE, AP_GROUND, 0);
  int ok = ap_builder_create(nm, &b) == AP_OK && ap_builder_add_body(b, &d, NULL) == AP_OK &&
           ap_builder_add_joint(b, &j, NULL) == AP_OK && ap_builder_compile(b, &om) == AP_OK;
  const char *got = ok ? ap_model_name(om) : "";
  ok = ok && strlen(got) == 63 && strcmp(got + 60, "...") == 0 && strncmp(got, nm, 60) == 0;
  ap_model_free(om), om = NULL;
  ap_builder_free(b);
  return ok;
}

static const char *const no_words[3] = {"mass", "masses", NULL};

static void cases_status_system(void) {
  CASE(ap_strerror, "unknown code", ap_strerror(12345) && ap_strerror(12345)[0]);
  CASE(ap_strerror, "INT_MIN", ap_strerror(INT_MIN) != NULL);
  CASE(ap_suggest, "word NULL", ap_suggest(NULL, no_words, -1) == NULL);
  CASE(ap_suggest, "words NULL", ap_suggest("mass", NULL, 3) == NULL);
  CASE(ap_suggest, "count 0", ap_suggest("mass", no_words, 0) == NULL);
  CASE(ap_suggest, "a close word (case-insensitive)",
       ap_suggest("MAS", no_words, -1) == no_words[0]);
  CASE(ap_suggest, "no close word", ap_suggest("inertia", no_words, 2) == NULL);
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
  CASE(ap_model_from_system, "def zeroed, not from ap_system_def_default",
       refused_with((ap_system_def){0}, "") &&
           not_default_msg(msg, "ap_system_def", "system"));
  CASE(ap_model_from_system, "def valid but internal_check 0",
       refused(unchecked_sys()) && not_default_msg(msg, "ap_system_def", NULL));
  CASE(ap_model_from_system, "k = 46341: k x k past INT_MAX (32-bit LAPACK)",
       refused_with(sysdef(46341, 46341, 0), "32-bit LAPACK") &&
           strstr(msg, "2147488281"));
  CASE(ap_model_from_system, "k = 46340, the largest dense k, accepted",
       accepted(46340, AP_BIAS_ZERO));
  CASE(ap_model_from_system, "Christoffel n = k = 1291: n k^2 past INT_MAX",
       refused_with(sysdef(1291, 1291, 0), "n x k x k array dg/dq"));
  CASE(ap_model_from_system, "Christoffel n = k = 1290 accepted",
       accepted(1290, AP_BIAS_CHRISTOFFEL));
  CASE(ap_model_from_system, "b = 46341, k = 46340: b (k + 1) past INT_MAX",
       refused_with(sysdef(46340, 46340, 46341), "b x (k + 1)"));
  CASE(ap_model_from_system, "a name past 63 bytes ends in \"...\"", long_name_cut());
  CASE(ap_model_free, "NULL", (ap_model_free(NULL), 1));
  CASE(ap_model_n, "NULL", ap_model_n(NULL) == AP_ERR_ARG);
  CASE(ap_model_path, "NULL", ap_model_path(NULL) == AP_ERR_ARG);
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
  CASE(ap_impact, "m NULL", ap_impact(NULL, SD, v, v, &T) == AP_ERR_ARG);
  CASE(ap_impact, "d NULL", ap_impact(SM, NULL, v, v, &T) == AP_ERR_ARG);
  CASE(ap_impact, "v_minus NULL", ap_impact(SM, SD, NULL, v, &T) == AP_ERR_ARG);
  CASE(ap_impact, "v_plus NULL", ap_impact(SM, SD, v, NULL, &T) == AP_ERR_ARG);
  CASE(ap_impact, "d of another model", ap_impact(SM, TD, v, v, &T) == AP_ERR_ARG);
  CASE(ap_impact, "loss NULL (optional)", ap_impact(SM, SD, v, v, NULL) == AP_OK);
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
  CASE(ap_sim_create, "def zeroed, not from ap_sim_def_default",
       sim_create_def((ap_sim_def){0}) && not_default_msg(msg, "ap_sim_def", NULL));
  CASE(ap_sim_create, "def valid but internal_check 0",
       sim_create_def((bad = simdef(), bad.internal_check = 0, bad)) &&
           not_default_msg(msg, "ap_sim_def", NULL));
  bad = simdef();
  CASE(ap_crosscheck, "def zeroed, not from ap_sim_def_default",
       ap_crosscheck(BM, &(ap_sim_def){0}, 0, q, v, 1, 2, &rep, msg, sizeof msg) == AP_ERR_ARG &&
           not_default_msg(msg, "ap_sim_def", NULL));
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
  CASE(ap_sim_failed_state, "s NULL", ap_sim_failed_state(NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_sim_failed_state, "no failure",
       ap_sim_failed_state(S, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_sim_free, "NULL", (ap_sim_free(NULL), 1));
  ap_event_def ev = ap_event_def_default();
  CASE(ap_event_def_default, "defaults", strcmp(ev.name, "event") == 0 && !ev.fn &&
       ev.action == AP_EVENT_STOP && ev.direction == AP_EVENT_EITHER);
  CASE(ap_sim_add_event, "s NULL", ap_sim_add_event(NULL, &ev) == AP_ERR_ARG);
  CASE(ap_sim_add_event, "def NULL", ap_sim_add_event(S, NULL) == AP_ERR_ARG);
  CASE(ap_sim_add_event, "fn NULL", ap_sim_add_event(S, &ev) == AP_ERR_ARG);
  ap_event_def evz = {.name = "zeroed", .fn = time_event};
  CASE(ap_sim_add_event, "def not from ap_event_def_default",
       ap_sim_add_event(S, &evz) == AP_ERR_ARG &&
           not_default_msg(ap_sim_message(S), "ap_event_def", "zeroed"));
  CASE(ap_sim_event_count, "NULL", ap_sim_event_count(NULL) == 0);
  ap_event_record er;
  CASE(ap_sim_event_get, "s NULL", ap_sim_event_get(NULL, 0, &er) == AP_ERR_ARG);
  CASE(ap_sim_event_get, "i out of range", ap_sim_event_get(S, 0, &er) == AP_ERR_ARG);
  CASE(ap_sim_event_get, "out NULL", ap_sim_event_get(S, 0, NULL) == AP_ERR_ARG);
  CASE(ap_sim_contact_mode, "s NULL", ap_sim_contact_mode(NULL, 0) == AP_ERR_ARG);
  CASE(ap_sim_contact_mode, "no contact modes", ap_sim_contact_mode(S, 0) == AP_ERR_ARG);
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
  CASE(ap_builder_add_body, "def zeroed, not from ap_body_def_default",
       ap_builder_add_body(B, &(ap_body_def){.name = "wheel", .mass = 1}, &id) == AP_ERR_ARG &&
           not_default_msg(ap_builder_message(B), "ap_body_def", "wheel"));
  CASE(ap_builder_add_joint, "def zeroed (parent 0, not the ground): refused",
       ap_builder_add_joint(B, &(ap_joint_def){.name = "hinge", .child = 0}, &id) ==
               AP_ERR_ARG &&
           not_default_msg(ap_builder_message(B), "ap_joint_def", "hinge"));
  CASE(ap_builder_add_joint, "def zeroed, unnamed: named by its id",
       ap_builder_add_joint(B, &(ap_joint_def){.child = 0}, &id) == AP_ERR_ARG &&
           strstr(ap_builder_message(B), "ap_joint_def (joint 0) was not made by "
                                         "ap_joint_def_default()"));
  CASE(ap_builder_add_constraint, "def zeroed, not from ap_constraint_def_default",
       ap_builder_add_constraint(B, &(ap_constraint_def){.name = "roll"}, &id) == AP_ERR_ARG &&
           not_default_msg(ap_builder_message(B), "ap_constraint_def", "roll"));
  CASE(ap_builder_add_effect, "def zeroed (gravity 0, not -9.81): refused",
       ap_builder_add_effect(B, &(ap_effect_def){.name = "gravity"}, &id) == AP_ERR_ARG &&
           not_default_msg(ap_builder_message(B), "ap_effect_def", "gravity"));
  CASE(ap_builder_add_effect, "def valid but internal_check 0",
       (ed.internal_check = 0, ap_builder_add_effect(B, &ed, &id) == AP_ERR_ARG &&
                                   not_default_msg(ap_builder_message(B), "ap_effect_def",
                                                   NULL)));
  ed = ap_effect_def_default();
  CASE(ap_builder_create, "a name past 63 bytes ends in \"...\"", long_builder_name());
  CASE(ap_builder_set_path, "b NULL", ap_builder_set_path(NULL, AP_PATH_TREE) == AP_ERR_ARG);
  CASE(ap_builder_set_path, "unknown path", ap_builder_set_path(B, (ap_path)9) == AP_ERR_ARG);
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

void api_cases_low(void) {
  cases_status_system();
  cases_core();
  cases_sim();
  cases_builder();
}
