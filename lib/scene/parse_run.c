/* Scene parsing, part 3: the initial state, the simulation settings and the outputs
 * (docs/scenes.md "initial", "simulation", "output").
 *
 * The initial state is read per joint in the coordinates people use (position, heading, tilt,
 * spin and their rates, or yaw, pitch, roll) into sc_init; init.c turns it into q0 and v0. Each
 * joint kind accepts its own keys. Simulation settings fill an ap_sim_def from
 * ap_sim_def_default(), so the defaults are the library's. Invariant: the run settings are
 * checked here (t_end > t0, positive tolerances, a known method), so a scene that loads runs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static const char *const sim_keys[] = {"mode", "method", "rtol", "atol", "t0", "t_end",
                                       "h_fixed", "h_init", "h_max", "max_steps", "rank_rtol",
                                       "switch_growth", "path", "compile", NULL};
static const char *const modes[] = {"minimal", "projected", "dae", "plain", NULL};  /* ap_mode */
static const char *const paths[] = {"auto", "dense", "tree", NULL};   /* ap_path */
static const char *const compiles[] = {"never", "auto", "always", NULL};  /* ap_compile_mode */
static const char *const out_keys[] = {"interval", "channels", NULL};

/* Keys of the initial state by joint kind. */
#define ORIENT_KEYS                                                                        \
  "quat", "heading", "tilt", "spin", "yaw", "pitch", "roll", "omega", "omega_body",        \
      "heading_rate", "tilt_rate", "spin_rate", "yaw_rate", "pitch_rate", "roll_rate"
static const char *const init_rev[] = {"angle", "rate", NULL};
static const char *const init_pri[] = {"position", "rate", NULL};
static const char *const init_pla[] = {"x", "y", "heading", "vx", "vy", "heading_rate", NULL};
static const char *const init_bal[] = {ORIENT_KEYS, NULL};
static const char *const init_fre[] = {"x", "y", "z", "vx", "vy", "vz", ORIENT_KEYS, NULL};
static const char *const init_con[] = {"x", "y", "vx", "vy", ORIENT_KEYS, NULL};
static const char *const init_fix[] = {NULL};

const char *const *sc_init_keys(ap_joint_kind kind) {
  switch (kind) {
    case AP_JOINT_REVOLUTE: return init_rev;
    case AP_JOINT_PRISMATIC: return init_pri;
    case AP_JOINT_PLANAR: return init_pla;
    case AP_JOINT_BALL: return init_bal;
    case AP_JOINT_FREE: return init_fre;
    case AP_JOINT_PLANE_CONTACT: return init_con;
    default: return init_fix;
  }
}

/* Read scalar keys into values and flags (e.g. x y z -> pos[0..2]). */
static int read_group(sc_ctx *c, const sc_node *n, const char *const *names, int count,
                      double *val, int *given) {
  for (int i = 0; i < count; i++) {
    const sc_node *v = names[i] ? sc_map_get(n, names[i]) : NULL;
    if (!v) continue;
    if (sc_number(c, v, &val[i])) return AP_ERR_ARG;
    if (given) given[i] = 1;
  }
  return AP_OK;
}

static int any_key(const sc_node *n, const char *const *names, int count) {
  for (int i = 0; i < count; i++)
    if (names[i] && sc_map_get(n, names[i])) return 1;
  return 0;
}

static const char *const zxz[] = {"heading", "tilt", "spin"};
static const char *const zyx[] = {"yaw", "pitch", "roll"};
static const char *const zxz_rates[] = {"heading_rate", "tilt_rate", "spin_rate"};
static const char *const zyx_rates[] = {"yaw_rate", "pitch_rate", "roll_rate"};

/* Orientation: quat | heading tilt spin | yaw pitch roll; angular velocity: omega |
 * omega_body | Euler rates of the same convention. */
static int read_orientation(sc_ctx *c, const sc_node *n, sc_init *in) {
  int q = sc_map_get(n, "quat") != NULL, a = any_key(n, zxz, 3), b = any_key(n, zyx, 3);
  if (q + a + b > 1)
    return sc_err(c, n, "give one orientation: quat, or heading/tilt/spin (Z-X-Z), or "
                  "yaw/pitch/roll (Z-Y-X)");
  in->orient = q ? 1 : a ? 2 : b ? 3 : 0;
  if (sc_get_vec(c, n, "quat", 4, in->quat) || read_group(c, n, a ? zxz : zyx, 3, in->euler, NULL))
    return AP_ERR_ARG;
  if (q && !(fabs(in->quat[0]) + fabs(in->quat[1]) + fabs(in->quat[2]) + fabs(in->quat[3]) > 0))
    return sc_err(c, sc_map_get(n, "quat"), "the quaternion must not be zero");
  int w = sc_map_get(n, "omega") != NULL, wb = sc_map_get(n, "omega_body") != NULL;
  int ra = any_key(n, zxz_rates, 3), rb = any_key(n, zyx_rates, 3);
  if (w + wb + ra + rb > 1)
    return sc_err(c, n, "give one angular velocity: omega, omega_body, or the rates of one "
                  "Euler convention");
  if ((ra && b) || (rb && a) || ((ra || rb) && q))
    return sc_err(c, n, "Euler rates need the angles of the same convention (%s)",
                  ra ? "heading, tilt, spin" : "yaw, pitch, roll");
  if (ra || rb) in->orient = ra ? 2 : 3;
  in->ang = w ? 1 : wb ? 2 : (ra || rb) ? 3 : 0;
  if (sc_get_vec(c, n, "omega", 3, in->omega) || sc_get_vec(c, n, "omega_body", 3, in->omega) ||
      read_group(c, n, ra ? zxz_rates : zyx_rates, 3, in->rates, NULL))
    return AP_ERR_ARG;
  return AP_OK;
}

static int read_init_kind(sc_ctx *c, const sc_node *n, sc_joint *j) {
  sc_init *in = &j->init;
  static const char *const xyz[] = {"x", "y", "z"}, *const vxyz[] = {"vx", "vy", "vz"};
  static const char *const pla[] = {"x", "y", "heading"}, *const vpla[] = {"vx", "vy",
                                                                            "heading_rate"};
  switch (j->def.kind) {
    case AP_JOINT_REVOLUTE:
      return read_group(c, n, (const char *const[]){"angle"}, 1, in->pos, in->pos_given) ||
             read_group(c, n, (const char *const[]){"rate"}, 1, in->vel, in->vel_given);
    case AP_JOINT_PRISMATIC:
      return read_group(c, n, (const char *const[]){"position"}, 1, in->pos, in->pos_given) ||
             read_group(c, n, (const char *const[]){"rate"}, 1, in->vel, in->vel_given);
    case AP_JOINT_PLANAR:
      return read_group(c, n, pla, 3, in->pos, in->pos_given) ||
             read_group(c, n, vpla, 3, in->vel, in->vel_given);
    case AP_JOINT_FREE:
    case AP_JOINT_PLANE_CONTACT: {
      int m = j->def.kind == AP_JOINT_FREE ? 3 : 2;
      if (read_group(c, n, xyz, m, in->pos, in->pos_given) ||
          read_group(c, n, vxyz, m, in->vel, in->vel_given))
        return AP_ERR_ARG;
    }
      /* fall through */
    case AP_JOINT_BALL: return read_orientation(c, n, in);
    default: return AP_OK;
  }
}

/* A driven coordinate takes its value from the drive: refuse an initial value for it. */
int sc_check_driven(sc_ctx *c, const sc_node *n, const sc_joint *j) {
  for (int i = 0; i < n->n; i++) {
    const char *k = n->keys[i]->text;
    int idx = sc_joint_drivable(j->def.kind, k);
    if (idx >= 0 && j->def.drive[idx])
      return sc_err(c, n->kids[i], "coordinate '%s' of joint '%s' is driven; its initial value "
                    "comes from the drive", k, j->name);
  }
  return AP_OK;
}

static int parse_initial(sc_ctx *c, sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "initial");
  if (!n) return AP_OK;
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  for (int i = 0; i < n->n; i++) {
    int j = sc_find_joint(s, n->keys[i]->text);
    if (j < 0) {
      const char **names = calloc((size_t)s->nj + 1, sizeof *names);
      for (int k = 0; names && k < s->nj; k++) names[k] = s->joints[k].name;
      const char *sug = names ? sc_suggest(n->keys[i]->text, names) : NULL;
      sc_err(c, n->keys[i], "no joint named '%s'%s%s%s (the initial state is given per joint)",
             n->keys[i]->text, sug ? " (did you mean '" : "", sug ? sug : "", sug ? "'?)" : "");
      free(names);
      return AP_ERR_ARG;
    }
    sc_joint *jt = &s->joints[j];
    jt->init.node = n->kids[i];
    if (sc_check_keys(c, n->kids[i], sc_init_keys(jt->def.kind)) ||
        sc_check_driven(c, n->kids[i], jt) ||
        read_init_kind(c, n->kids[i], jt))
      return AP_ERR_ARG;
  }
  return AP_OK;
}

/* ---- simulation and output -------------------------------------------------------------- */

static int parse_method(sc_ctx *c, sc_scene *s, const sc_node *sim) {
  const char *name = NULL;
  if (sc_get_name(c, sim, "method", &name) || !name) return c->status;
  ap_method_info info;
  if (ap_method_find(name, &info) == AP_OK) {
    snprintf(s->method, sizeof s->method, "%s", info.name);
    return AP_OK;
  }
  const char *names[64] = {NULL};
  int nm = ap_method_count();
  for (int i = 0; i < nm && i < 63; i++)
    if (ap_method_get(i, &info) == AP_OK) names[i] = info.name;
  const char *sug = sc_suggest(name, names);
  return sc_err(c, sc_map_get(sim, "method"), "unknown method '%s'%s%s%s (appell run --help "
                "lists them)", name, sug ? " (did you mean '" : "", sug ? sug : "",
                sug ? "'?)" : "");
}

static int parse_sim(sc_ctx *c, sc_scene *s) {
  ap_scene_run *r = &s->run;
  const sc_node *n = sc_map_get(s->root, "simulation");
  int mode = (int)r->sim.mode;
  s->compile = -1;
  if (!n) return AP_OK;
  if (sc_check_keys(c, n, sim_keys) || sc_get_enum(c, n, "mode", modes, &mode) ||
      sc_get_enum(c, n, "path", paths, &s->path) ||
      sc_get_enum(c, n, "compile", compiles, &s->compile) ||
      parse_method(c, s, n) || sc_get_number(c, n, "rtol", &r->sim.rtol) ||
      sc_get_number(c, n, "atol", &r->sim.atol) || sc_get_number(c, n, "t0", &r->t0) ||
      sc_get_number(c, n, "t_end", &r->t_end) || sc_get_number(c, n, "h_fixed", &r->sim.h_fixed) ||
      sc_get_number(c, n, "h_init", &r->sim.h_init) ||
      sc_get_number(c, n, "h_max", &r->sim.h_max) ||
      sc_get_int(c, n, "max_steps", &r->sim.max_steps) ||
      sc_get_number(c, n, "rank_rtol", &r->sim.rank_rtol) ||
      sc_get_number(c, n, "switch_growth", &r->sim.switch_growth))
    return AP_ERR_ARG;
  r->sim.mode = (ap_mode)mode;
  if (s->path == AP_PATH_TREE && r->sim.mode == AP_MODE_DAE)   /* ap_sim_create would refuse */
    return sc_err(c, sc_map_get(n, "path"), "path: tree forms no g or A, which mode: dae needs "
                  "(path: dense, or auto, which keeps dae scenes dense)");
  if (sc_check_positive(c, n, "rtol", r->sim.rtol) ||
      sc_check_positive(c, n, "atol", r->sim.atol) ||
      sc_check_positive(c, n, "h_fixed", r->sim.h_fixed) ||
      sc_check_nonneg(c, n, "h_init", r->sim.h_init) ||
      sc_check_nonneg(c, n, "h_max", r->sim.h_max) ||
      sc_check_positive(c, n, "rank_rtol", r->sim.rank_rtol) ||
      sc_check_positive(c, n, "max_steps", (double)r->sim.max_steps))
    return AP_ERR_ARG;
  if (!(r->sim.rank_rtol < 1))   /* |R_ii| > rank_rtol |R_00| with rank_rtol >= 1: rank 1 */
    return sc_err(c, sc_map_get(n, "rank_rtol"), "must be below 1 (got %g; default 1e-10)",
                  r->sim.rank_rtol);
  if (r->sim.switch_growth < 1)
    return sc_err(c, sc_map_get(n, "switch_growth"), "must be >= 1 (got %g)",
                  r->sim.switch_growth);
  if (!(r->t_end > r->t0) && sc_map_get(n, "t_end"))
    return sc_err(c, sc_map_get(n, "t_end"), "must be after t0 (got %g, t0 = %g)", r->t_end,
                  r->t0);
  if (!(r->t_end > r->t0))
    return sc_err(c, n, "t_end (%g by default) must be after t0 (%g)", r->t_end, r->t0);
  return AP_OK;
}

static int parse_channels(sc_ctx *c, sc_scene *s, const sc_node *ch) {
  static const char *const names[] = SC_OUT_NAMES;
  if (sc_expect(c, ch, SC_SEQ)) return AP_ERR_ARG;
  s->channels = 0;
  for (int i = 0; i < ch->n; i++) {
    const sc_node *it = ch->kids[i];
    int k = -1;
    if (it->kind == SC_MAP) {   /* NAME: EXPRESSION (channels.c) */
      if (sc_parse_named_channels(c, s, it)) return AP_ERR_ARG;
      continue;
    }
    if (sc_expect(c, it, SC_SCALAR)) return AP_ERR_ARG;
    for (int j = 0; names[j]; j++)
      if (strcmp(it->text, names[j]) == 0) k = j;
    if (k < 0) {
      const char *sug = sc_suggest(it->text, names);
      return sc_err(c, it, "unknown channel '%s'%s%s%s (channels: coordinates, speeds, angles, "
                    "com, contacts, energy, residual, reactions, contact_forces, poses, driven; or "
                    "NAME: EXPRESSION)", it->text,
                    sug ? " (did you mean '" : "", sug ? sug : "", sug ? "'?)" : "");
    }
    s->channels |= 1u << k;
  }
  return AP_OK;
}

static int parse_output(sc_ctx *c, sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "output");
  if (!n) return AP_OK;
  if (sc_check_keys(c, n, out_keys) || sc_get_number(c, n, "interval", &s->run.interval) ||
      sc_check_positive(c, n, "interval", s->run.interval))
    return AP_ERR_ARG;
  const sc_node *ch = sc_map_get(n, "channels");
  return ch ? parse_channels(c, s, ch) : AP_OK;
}

int sc_parse_run(sc_ctx *c, sc_scene *s) {
  s->run.sim = ap_sim_def_default();
  snprintf(s->method, sizeof s->method, "%s", s->run.sim.method ? s->run.sim.method : "dopri5");
  s->run.t0 = 0.0, s->run.t_end = 10.0, s->run.interval = 0.01;
  s->channels = SC_OUT_COORDS | SC_OUT_SPEEDS | SC_OUT_ENERGY | SC_OUT_RESIDUAL;
  if (parse_initial(c, s) || parse_sim(c, s) || parse_output(c, s)) return AP_ERR_ARG;
  s->run.sim.method = s->method;
  if ((s->run.t_end - s->run.t0) / s->run.interval > 1e7)
    return sc_err(c, sc_map_get(s->root, "output") ? sc_map_get(s->root, "output") : s->root,
                  "more than 10^7 output rows (t_end - t0 = %g, interval %g)",
                  s->run.t_end - s->run.t0, s->run.interval);
  return AP_OK;
}
