/* Scene API (include/appell/scene.h): load = read the file, build the tree, apply the --set
 * overrides, parse, build and compile; then the initial state, the output rows and listings.
 *
 * An ap_scene owns its tree (element names point into it), the parsed scene (expressions the
 * model's callbacks use), the model, one data struct for output evaluation and the output
 * columns. Invariant: the model is freed before the expressions it calls, and a failed load
 * frees everything and leaves exactly one message. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/text.h"
#include "appell/compiled.h"
#include "codegen/codegen.h"
#include "scene/scene_int.h"

#define SC_MAX_FILE (16L << 20)

struct ap_scene {
  sc_scene s;
  ap_model *m;
  ap_data *d;              /* scratch for outputs, energy and residuals */
  sc_out out;
  char name[64];
  char compile_notice[600];   /* why simulation.compile fell back to the interpreted path */
};

void sc_scene_clear(sc_scene *s) {
  for (int j = 0; j < s->nj; j++)
    for (int i = 0; i < 3; i++) sc_expr_free(&s->joints[j].drive[i]);
  for (int c = 0; c < s->nc; c++) {
    sc_expr_free(&s->cons[c].value);
    sc_expr_free(&s->cons[c].ground.omega);
    for (int i = 0; i < 2; i++) sc_expr_free(&s->cons[c].ground.vel[i]);
    sc_expr_free(&s->cons[c].ground.height);
  }
  for (int e = 0; e < s->ne; e++) {
    for (int i = 0; i < 3; i++) {
      sc_expr_free(&s->effs[e].force[i]);
      sc_expr_free(&s->effs[e].torque[i]);
    }
    sc_expr_free(&s->effs[e].value);
  }
  sc_expr_free(&s->ground.omega);
  for (int i = 0; i < 2; i++) sc_expr_free(&s->ground.vel[i]);
  sc_expr_free(&s->ground.height);
  sc_events_free(s);
  sc_params_free(s->params);
  sc_strings_free(&s->strings);
  sc_named_free(s);
  free(s->bodies);
  free(s->joints);
  free(s->cons);
  free(s->effs);
  sc_tree_free(s->root);
  free(s->file);
  memset(s, 0, sizeof *s);
}

void ap_scene_free(ap_scene *sc) {
  if (!sc) return;
  ap_data_free(sc->d);
  ap_model_free(sc->m);
  sc_out_free(&sc->out);
  sc_scene_clear(&sc->s);
  free(sc);
}

/* The file name without directory and extension. */
static void stem(const char *file, char *out, size_t len) {
  const char *base = strrchr(file, '/');
  base = base ? base + 1 : file;
  size_t n = strcspn(base, ".");
  char whole[4096];   /* a file name has at most 255 bytes: whole always holds the stem */
  snprintf(whole, sizeof whole, "%.*s", (int)(n < sizeof whole ? n : sizeof whole - 1), base);
  ap_core_copy_name(out, len, whole[0] ? whole : "scene");   /* "..." when cut */
}

/* A --set of the parts: or instances: sections ("instances.rl.parameters.y=0.5"). */
static int sets_parts(const char *set) {
  size_t n = strcspn(set, ".[=");
  return (n == 5 && strncmp(set, "parts", 5) == 0) || (n == 9 && strncmp(set, "instances", 9) == 0);
}

/* The independent speeds of the partition at the scene's initial state (ap_partition), for the
 * compiled acceleration stage's variant (lib/codegen): 0 when there is none to expect. */
static int initial_indep(ap_scene *sc, int *indep) {
  const ap_model *m = sc->m;
  ap_data *d = NULL;
  int got = 0, l = m->k - m->b;
  if (!ap_model_is_body_model(m) || m->ops || m->b <= 0 || l <= 0 || l > 64 ||
      ap_data_create(m, &d) != AP_OK)
    return 0;
  if (ap_scene_initial_state(sc, d->q, d->v, NULL, 0, NULL, 0) == AP_OK) {
    d->t = sc->s.run.t0;
    got = ap_partition(m, d) == AP_OK && d->rank == m->b;
    for (int i = 0; got && i < l; i++) indep[i] = d->perm[m->b + i];
  }
  ap_data_free(d);
  return got;
}

/* simulation.compile, else $APPELL_COMPILE, else never (docs/compiled.md). */
static void compile_model(ap_scene *sc) {
  ap_compile_mode mode = AP_COMPILE_NEVER;
  const char *env = getenv("APPELL_COMPILE");
  if (sc->s.compile >= 0) mode = (ap_compile_mode)sc->s.compile;
  else if (env && env[0] && ap_compile_mode_parse(env, &mode) != AP_OK)
    snprintf(sc->compile_notice, sizeof sc->compile_notice, "appell: APPELL_COMPILE='%.40s' is "
             "not never, auto or always: ignored", env);
  int indep[64];
  if (mode != AP_COMPILE_NEVER)
    cg_compile_hinted(sc->m, mode, initial_indep(sc, indep) ? indep : NULL, sc->compile_notice,
                      sizeof sc->compile_notice);
}

const char *ap_scene_compile_notice(const ap_scene *s) {
  return s ? s->compile_notice : "";
}

static int load_parsed(sc_ctx *c, ap_scene *sc) {
  if (sc_parse_scene(c, &sc->s) != AP_OK) return c->status;
  if (!sc->s.name) sc->s.name = sc->name;
  if (sc_build(c, &sc->s, &sc->m) != AP_OK) return c->status;
  compile_model(sc);
  if (sc_events_bind(c, &sc->s, sc->m) != AP_OK) return c->status;
  if (sc_inputs_check(c, &sc->s, sc->m) != AP_OK) return c->status;
  if (ap_data_create(sc->m, &sc->d) != AP_OK || sc_out_names(&sc->out, &sc->s, sc->m) != AP_OK)
    return sc_nomem(c);
  return AP_OK;
}

int ap_scene_load_string(const char *text, size_t len, const char *name,
                         const char *const *sets, int nsets, ap_scene **out, char *msg,
                         size_t msg_len) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  int bad = nsets < 0 || (nsets > 0 && !sets) ? 0 : -1;   /* the first bad override */
  for (int i = 0; bad < 0 && i < nsets; i++)
    if (!sets[i]) bad = i + 1;
  if (bad >= 0) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s: overrides: %d given, %s is NULL",
                                 name ? name : "scene", nsets, bad ? "one" : "the array");
    return AP_ERR_ARG;
  }
  if (len > (size_t)SC_MAX_FILE) {
    if (msg && msg_len)
      snprintf(msg, msg_len, "%s: larger than 16 MiB: not a scene file", name ? name : "scene");
    return AP_ERR_ARG;
  }
  ap_scene *sc = calloc(1, sizeof *sc);
  sc_ctx c = {name ? name : "scene", "", AP_OK};
  if (!sc || !text) {
    free(sc);
    if (msg && msg_len) snprintf(msg, msg_len, "%s", sc ? "NULL scene text" : "out of memory");
    return sc ? AP_ERR_ARG : AP_ERR_NOMEM;
  }
  sc->s.file = strdup(c.file);
  if (!sc->s.file) sc_nomem(&c);   /* includes are found from the file's name: no guessing */
  c.file = sc->s.file ? sc->s.file : "scene";
  stem(c.file, sc->name, sizeof sc->name);
  if (c.status == AP_OK) sc->s.root = sc_tree_load(&c, text, len);
  if (sc->s.root && sc->s.root->kind != SC_MAP)
    sc_err(&c, sc->s.root, "a scene is a mapping of sections (bodies:, joints:, ...)");
  if (c.status == AP_OK) sc_include_expand(&c, sc->s.root, c.file, &sc->s.strings);
  /* --set of parts and instances before they are copied, every other one after: it may
   * change an element an instance defines (joints.front_wheel.parent_frame.pos.0=...) */
  for (int i = 0; c.status == AP_OK && i < nsets; i++)
    if (sets_parts(sets[i])) sc_tree_set(&c, sc->s.root, sets[i]);
  if (c.status == AP_OK) sc_parts_expand(&c, sc->s.root, &sc->s.strings);
  for (int i = 0; c.status == AP_OK && i < nsets; i++)
    if (!sets_parts(sets[i])) sc_tree_set(&c, sc->s.root, sets[i]);
  if (c.status == AP_OK) sc_params_read(&c, sc->s.root, &sc->s.params);
  if (c.status == AP_OK) load_parsed(&c, sc);
  if (c.status != AP_OK) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s", c.msg);
    int rc = c.status;
    ap_scene_free(sc);
    return rc;
  }
  *out = sc;
  return AP_OK;
}

/* Read all of f (at most SC_MAX_FILE bytes; hint: the size when known). 0, or an errno value,
 * or EFBIG when the file is larger. */
static int read_all(FILE *f, size_t hint, char **out, size_t *len) {
  size_t cap = hint + 1 > (size_t)SC_MAX_FILE + 1 ? (size_t)SC_MAX_FILE + 1 : hint + 1, n = 0;
  char *buf = NULL;
  for (;;) {
    if (n == cap || !buf) {
      if (buf) cap = cap > (size_t)SC_MAX_FILE / 2 ? (size_t)SC_MAX_FILE + 1 : 2 * cap;
      char *b = realloc(buf, cap);
      if (!b) return free(buf), ENOMEM;
      buf = b;
    }
    n += fread(buf + n, 1, cap - n, f);
    if (ferror(f)) return free(buf), errno ? errno : EIO;
    if (n > (size_t)SC_MAX_FILE) return free(buf), EFBIG;
    if (feof(f) && n < cap) break;
  }
  *out = buf, *len = n;
  return 0;
}

int ap_scene_read(const char *path, char **text, size_t *len, char *msg, size_t msg_len) {
  if (text) *text = NULL;
  if (len) *len = 0;
  if (!text || !len) return AP_ERR_ARG;
  errno = 0;
  FILE *f = path ? fopen(path, "rb") : NULL;
  char ebuf[128];
  if (!f) {
    int open_err = path ? errno : EINVAL;
    if (msg && msg_len) snprintf(msg, msg_len, "%s: cannot open: %s", path ? path : "(null)",
                                 ap_core_errno_text(open_err, ebuf, sizeof ebuf));
    errno = open_err;
    return AP_ERR_ARG;
  }
  struct stat st;   /* read only when fstat succeeds; otherwise read the stream as it comes */
  int known = fstat(fileno(f), &st) == 0, dir = known && S_ISDIR(st.st_mode);
  size_t hint = known && S_ISREG(st.st_mode) ? (size_t)st.st_size : 65536;
  int err = dir ? EISDIR : read_all(f, hint, text, len);
  fclose(f);
  errno = 0;
  if (!err) return (*text)[*len] = '\0', AP_OK;
  if (msg && msg_len)
    snprintf(msg, msg_len, "%s: %s", path, err == EISDIR ? "is a directory, not a scene file"
             : err == EFBIG ? "larger than 16 MiB: not a scene file"
             : ap_core_errno_text(err, ebuf, sizeof ebuf));
  errno = 0;
  return err == ENOMEM ? AP_ERR_NOMEM : AP_ERR_ARG;
}

void ap_scene_text_free(char *text) { free(text); }

int ap_scene_load(const char *path, const char *const *sets, int nsets, ap_scene **out,
                  char *msg, size_t msg_len) {
  if (out) *out = NULL;
  char *buf = NULL;
  size_t len = 0;
  int rc = ap_scene_read(path, &buf, &len, msg, msg_len);
  if (rc == AP_OK) rc = ap_scene_load_string(buf, len, path, sets, nsets, out, msg, msg_len);
  free(buf);
  return rc;
}

const ap_model *ap_scene_model(const ap_scene *sc) { return sc ? sc->m : NULL; }
const ap_data *sc_scene_output_data(const ap_scene *sc) { return sc ? sc->d : NULL; }
const sc_scene *sc_scene_parsed(const ap_scene *sc) { return sc ? &sc->s : NULL; }
const char *ap_scene_name(const ap_scene *sc) { return sc ? sc->s.name : NULL; }

int ap_scene_body_visual(const ap_scene *sc, int body, ap_scene_visual *out) {
  if (!sc || !out || body < 0 || body >= sc->s.nb) return AP_ERR_ARG;
  *out = sc->s.bodies[body].visual;
  return AP_OK;
}

void ap_scene_get_run(const ap_scene *sc, ap_scene_run *run) {
  if (sc && run) *run = sc->s.run;
  else if (run) memset(run, 0, sizeof *run);
}

int ap_scene_initial_state(ap_scene *sc, double *q0, double *v0, char *report,
                           size_t report_len, char *msg, size_t msg_len) {
  if (!sc || !q0 || !v0) return AP_ERR_ARG;
  sc_ctx c = {sc->s.file, "", AP_OK};
  int rc = sc_check_exprs(&c, &sc->s, sc->s.run.t0);
  if (rc == AP_OK) rc = sc_initial_state(&c, &sc->s, sc->m, q0, v0, report, report_len);
  if (rc == AP_OK) rc = sc_check_state_exprs(&c, &sc->s, sc->m, sc->s.run.t0, q0, v0);
  if (rc == AP_OK) rc = sc_check_start(&c, &sc->s, sc->m, q0, v0);
  if (rc != AP_OK && msg && msg_len) snprintf(msg, msg_len, "%s", c.msg);
  return rc;
}

int ap_scene_check_time(const ap_scene *sc, double t, char *msg, size_t msg_len) {
  if (!sc) return AP_ERR_ARG;
  sc_ctx c = {sc->s.file, "", AP_OK};
  int rc = sc_check_exprs(&c, &sc->s, t);
  if (rc != AP_OK && msg && msg_len) snprintf(msg, msg_len, "%s", c.msg);
  return rc;
}

/* Finite entries only: a diverged state makes every expression of it look guilty. */
static int all_finite(const double *x, int n) {
  for (int i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

int ap_scene_locate_failure(const ap_scene *sc, const ap_sim *sim, double tout, char *msg,
                            size_t msg_len) {
  if (msg && msg_len) msg[0] = '\0';
  const ap_data *d = ap_sim_data(sim);
  if (!sc || !d) return AP_ERR_ARG;
  sc_ctx c = {sc->s.file, "", AP_OK};
  int n = ap_model_n(sc->m), k = ap_model_k(sc->m), rc = AP_OK;
  double t = d->t;   /* where the model was evaluated last: the failing state if any */
  const double *q = d->q, *v = d->v;
  ap_sim_failed_state(sim, &t, &q, &v);
  if (isfinite(t)) rc = sc_check_exprs(&c, &sc->s, t);
  if (rc == AP_OK && isfinite(t) && d->n == n && d->k == k && all_finite(q, n) &&
      all_finite(v, k))
    rc = sc_check_state_exprs(&c, &sc->s, sc->m, t, q, v);
  if (rc == AP_OK && isfinite(tout)) rc = sc_check_exprs(&c, &sc->s, tout);
  if (rc == AP_OK) return AP_OK;
  if (msg && msg_len) snprintf(msg, msg_len, "%s", c.msg);
  return AP_ERR_ARG;
}

int ap_scene_output_count(const ap_scene *sc) { return sc ? sc->out.ncols : 0; }

const char *ap_scene_output_name(const ap_scene *sc, int i) {
  return sc && i >= 0 && i < sc->out.ncols ? sc->out.cols[i] : NULL;
}

int ap_scene_output_row(ap_scene *sc, ap_sim *sim, double *row) {
  if (!sc || !sim || !row) return AP_ERR_ARG;
  const ap_data *sd = ap_sim_data(sim);   /* the simulation must be of the scene's model */
  if (sd->n != ap_model_n(sc->m) || sd->k != ap_model_k(sc->m) || sd->b != ap_model_b(sc->m))
    return AP_ERR_ARG;
  return sc_out_row(&sc->out, &sc->s, sc->m, sc->d, sim, row);
}

static void load_state(ap_scene *sc, double t, const double *q, const double *v) {
  sc->d->t = t;
  memcpy(sc->d->q, q, sizeof(double) * (size_t)ap_model_n(sc->m));
  memcpy(sc->d->v, v, sizeof(double) * (size_t)ap_model_k(sc->m));
}

int ap_scene_energy(ap_scene *sc, double t, const double *q, const double *v, double *E) {
  if (!sc || !q || !v || !E) return AP_ERR_ARG;
  double T = 0.0, V = 0.0;
  load_state(sc, t, q, v);
  int rc = sc_out_energy(sc->m, sc->d, &T, &V);
  *E = T + V;
  return rc;
}

int ap_scene_residual(ap_scene *sc, double t, const double *q, const double *v, double *resid) {
  if (!sc || !q || !v || !resid) return AP_ERR_ARG;
  load_state(sc, t, q, v);
  sc->d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(sc->m, sc->d);
  *resid = rc == AP_OK ? ap_constraint_residual(sc->d, v) : 0.0;
  return rc;
}

static int ground_moves(const ap_ground_motion *g, const sc_ground *sg) {
  if (g->kind == AP_GROUND_TURNTABLE) return sg->omega.timed || g->omega != 0.0;
  if (g->kind == AP_GROUND_TRANSLATING)
    return sg->vel[0].timed || sg->vel[1].timed || g->velocity[0] != 0.0 || g->velocity[1] != 0.0;
  return 0;
}

int ap_scene_conserves_energy(const ap_scene *sc) {
  if (!sc) return 0;
  const sc_scene *s = &sc->s;
  if (sc_scene_has_modes(s)) return 0;   /* sliding and touchdown impacts dissipate */
  for (int j = 0; j < s->nj; j++)
    for (int i = 0; i < 3; i++)
      if (s->joints[j].def.drive[i]) return 0;
  for (int c = 0; c < s->nc; c++) {
    const ap_constraint_def *d = &s->cons[c].def;
    if (d->kind == AP_CON_PRESCRIBED_SPEED && (s->cons[c].value.timed || d->speed_value != 0.0))
      return 0;
    if ((d->kind == AP_CON_ROLLING || d->kind == AP_CON_KNIFE_EDGE) &&
        ground_moves(&d->ground, &s->cons[c].ground))
      return 0;
  }
  for (int e = 0; e < s->ne; e++) {
    const ap_effect_def *d = &s->effs[e].def;
    if (d->kind == AP_EFFECT_JOINT_DAMPING && d->damping != 0.0) return 0;
    if (d->kind == AP_EFFECT_SPRING && d->damping != 0.0) return 0;
    if (d->kind == AP_EFFECT_APPLIED || d->kind == AP_EFFECT_JOINT_FORCE ||
        d->kind == AP_EFFECT_MOTOR)
      return 0;
  }
  return 1;
}

/* ---- listings --------------------------------------------------------------------------- */

int ap_scene_count(const ap_scene *sc, ap_scene_section sec) {
  if (!sc) return 0;
  static const char *const names[] = SC_OUT_NAMES;
  int n = 0;
  switch (sec) {
    case AP_SCENE_BODIES: return sc->s.nb;
    case AP_SCENE_JOINTS: return sc->s.nj;
    case AP_SCENE_CONSTRAINTS: return sc->s.nc;
    case AP_SCENE_EFFECTS: return sc->s.ne;
    case AP_SCENE_CHANNELS:
      for (int i = 0; names[i]; i++) n += (sc->s.channels >> i) & 1u;
      return n;
  }
  return 0;
}

static const char *channel(const ap_scene *sc, int i) {
  static const char *const names[] = SC_OUT_NAMES;
  for (int j = 0; names[j]; j++)
    if (((sc->s.channels >> j) & 1u) && i-- == 0) return names[j];
  return NULL;
}

const char *ap_scene_element_name(const ap_scene *sc, ap_scene_section sec, int i) {
  if (!sc || i < 0 || i >= ap_scene_count(sc, sec)) return NULL;
  switch (sec) {
    case AP_SCENE_BODIES: return sc->s.bodies[i].name;
    case AP_SCENE_JOINTS: return sc->s.joints[i].name;
    case AP_SCENE_CONSTRAINTS: return sc->s.cons[i].name;
    case AP_SCENE_EFFECTS: return sc->s.effs[i].name;
    case AP_SCENE_CHANNELS: return channel(sc, i);
  }
  return NULL;
}

const char *ap_scene_element_kind(const ap_scene *sc, ap_scene_section sec, int i) {
  static const char *const shapes[] = {"none", "point", "sphere", "ellipsoid", "disk", "torus"};
  static const char *const cons[] = {"rolling", "knife_edge", "prescribed_speed", "user",
                                     "coincident", "point_on_line", "point_on_plane"};
  static const char *const effs[] = {"gravity", "spring", "joint_damping", "applied", "user",
                                     "joint_force", "motor"};
  if (!sc || i < 0 || i >= ap_scene_count(sc, sec)) return NULL;
  switch (sec) {
    case AP_SCENE_BODIES:
      return sc->s.bodies[i].def.shape.kind ? shapes[sc->s.bodies[i].def.shape.kind] : "no shape";
    case AP_SCENE_JOINTS: return sc_joint_kind_name(sc->s.joints[i].def.kind);
    case AP_SCENE_CONSTRAINTS: return sc_con_kind_text(&sc->s.cons[i], cons);
    case AP_SCENE_EFFECTS:
      return sc->s.effs[i].is_torque ? "joint_torque" : effs[sc->s.effs[i].def.kind];
    case AP_SCENE_CHANNELS: return "channel";
  }
  return NULL;
}
