/* Appell scene layer (internal): the YAML tree, the reader context, expressions, and the
 * parsed scene.
 *
 * Layout of the layer (docs/scenes.md is the user's reference):
 *   tree.c    libyaml events -> sc_node tree with line:column of every node, within limits
 *   tree_set.c  --set overrides: edit the tree by key path before it is read
 *   read.c    typed getters on the tree, unknown-key checks ("did you mean"), messages
 *   expr.c    scene expressions: constants and functions of t, located messages
 *   expr_parse.c expr_eval.c expr_fn.c  the evaluator (expr.h): text -> program -> jets
 *   expr_scene.c every expression of a scene, and the initial state, checked at a time
 *   parse.c   tree -> sc_scene (bodies, joints, constraints, effects, ground)
 *   parse_run.c  tree -> initial state, simulation settings, outputs
 *   build.c   sc_scene -> ap_builder -> ap_model
 *   init.c    initial state in people's coordinates -> consistent (q0, v0)
 *   output.c  output channels: names and values of a CSV row
 *   scene.c   the public entry points (include/appell/scene.h)
 *   params.c  the parameters: section, named numbers that every expression may use
 *   include.c parts.c  include: of other files; parts: instantiated by instances:
 *
 * Invariant: every message the layer produces for bad input names the file, line and column
 * of the offending node and its key path, and at most one message is produced per load. */
#ifndef AP_SCENE_INT_H
#define AP_SCENE_INT_H

#include <stddef.h>

#include "appell/body.h"
#include "appell/scene.h"
#include "appell/sim.h"
#include "scene/expr.h"

/* ---- the tree (tree.c) ---------------------------------------------------------------- */

typedef enum sc_kind { SC_SCALAR = 0, SC_SEQ = 1, SC_MAP = 2 } sc_kind;

typedef struct sc_node {
  sc_kind kind;
  char *text;              /* scalar value (NUL-terminated; may hold NULs from the file) */
  int quoted;              /* scalar written in quotes: a string, never a number */
  int line, col;           /* 1-based position in the file; line 0 = from the command line */
  const char *origin;      /* the --set argument that created or changed the node, or NULL */
  char *path;              /* key path from the root, e.g. bodies.disk.com[1] */
  int n, cap;              /* children */
  struct sc_node **keys;   /* map: the key scalars (n) */
  struct sc_node **kids;   /* map values or sequence items (n) */
  const char *file;        /* the included file it was read from, or NULL: the scene's own */
  const char *inst;        /* "part 'P' as 'I' (FILE:LINE:COL)" for nodes of a part, or NULL */
  const struct sc_params *params;   /* the scene's parameters its expressions may name */
} sc_node;

/* Limits that keep hostile input (alias bombs, long keys above wide aliases, deep nesting)
 * cheap: a tree, counted as it is read with aliases expanded, has at most SC_MAX_NODES nodes,
 * SC_MAX_BYTES bytes (nodes, key paths, texts) and SC_MAX_DEPTH levels (docs/scenes.md). */
#define SC_MAX_DEPTH 64
#define SC_MAX_NODES 1000000
#define SC_MAX_BYTES (64L << 20)

/* The reader context: the file name and the first error. */
typedef struct sc_ctx {
  const char *file;
  char msg[1024];
  int status;              /* AP_OK or the first error's status */
} sc_ctx;

/* Parse YAML text into a tree. Returns NULL with ctx->msg set on failure. */
sc_node *sc_tree_load(sc_ctx *c, const char *text, size_t len);
/* The same, adding to *compares the string comparisons made by the duplicate-key and anchor
 * lookups (tests check that they grow linearly with the input). */
sc_node *sc_tree_load_counted(sc_ctx *c, const char *text, size_t len, long *compares);
/* Parse a --set value (a YAML flow sequence or mapping) into a tree whose root has path and
 * whose nodes carry origin and line 0. NULL with ctx->msg set on failure. */
sc_node *sc_tree_parse_value(sc_ctx *c, const char *text, const char *path, const char *origin);
void sc_tree_free(sc_node *root);
/* Apply "dotted.path=value" to the tree (tree_set.c has the rules). */
int sc_tree_set(sc_ctx *c, sc_node *root, const char *assignment);
/* Child of a map by key, or NULL. */
sc_node *sc_map_get(const sc_node *map, const char *key);
/* Node helpers shared by tree.c and tree_set.c. sc_node_new takes path (frees it on failure,
 * returns NULL when path is NULL); sc_node_push appends a child (and its key for maps). */
sc_node *sc_node_new(sc_kind kind, int line, int col, char *path);
int sc_node_push(sc_node *n, sc_node *key, sc_node *kid);
char *sc_strdup_len(const char *s, size_t len);
char *sc_child_path(const char *parent, const char *key, int index);   /* key or [index] */
/* Record "FILE: out of memory" (unless an error is recorded already); returns the status. */
int sc_nomem(sc_ctx *c);

/* ---- reading (read.c) ----------------------------------------------------------------- */

/* The leading minors m[0..2] of the 3 x 3 matrix inertia (column-major): all positive when the
 * symmetric matrix is positive definite (parse.c; the URDF import checks inertias with it too). */
void sc_leading_minors(const double *inertia, double m[3]);
/* Record an error at a node: "file:line:col: path: message". Returns AP_ERR_ARG. */
int sc_err(sc_ctx *c, const sc_node *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Every key of map must be in keys (NULL-terminated); otherwise an error naming the closest
 * allowed key. A non-map node is an error too ("expected a mapping"). */
int sc_check_keys(sc_ctx *c, const sc_node *map, const char *const *keys);
int sc_expect(sc_ctx *c, const sc_node *n, sc_kind kind);
/* The closest of keys to word by edit distance, or NULL when none is close. */
const char *sc_suggest(const char *word, const char *const *keys);
/* Scalars. Each leaves *out untouched when the key is absent (optional) and returns AP_OK. */
int sc_number(sc_ctx *c, const sc_node *n, double *out);   /* number or constant expression */
int sc_get_number(sc_ctx *c, const sc_node *map, const char *key, double *out);
int sc_get_vec(sc_ctx *c, const sc_node *map, const char *key, int len, double *out);
int sc_get_bool(sc_ctx *c, const sc_node *map, const char *key, int *out);
int sc_get_int(sc_ctx *c, const sc_node *map, const char *key, long *out);
/* A plain name (string scalar); *out points into the tree. */
int sc_get_name(sc_ctx *c, const sc_node *map, const char *key, const char **out);
/* One of words (NULL-terminated); *out = index. */
int sc_get_enum(sc_ctx *c, const sc_node *map, const char *key, const char *const *words,
                int *out);
/* Range checks with messages at the key's node. */
int sc_check_positive(sc_ctx *c, const sc_node *map, const char *key, double x);
int sc_check_nonneg(sc_ctx *c, const sc_node *map, const char *key, double x);

/* ---- expressions (expr.c; the evaluator: expr.h) ---------------------------------------- */

/* A scalar of the scene: a constant, or a compiled expression of t (and, through a symbol
 * table, of named variables). Never written after compile: safe to evaluate from threads. */
typedef struct sc_expr {
  int timed;               /* 0: the constant `value`; 1: `prog` (depends on t or variables) */
  double value;
  sc_prog *prog;           /* immutable program (timed only) */
  char *text;              /* its text (timed only) */
  const sc_node *node;     /* where it was read: the location of its messages */
} sc_expr;

/* Compile text read at node `at`; names allowed: t (when allow_t), pi, e, deg. A text that
 * folds to a number gives a constant. Errors: AP_ERR_ARG with the located message, or
 * AP_ERR_NOMEM (c->status too). */
int sc_expr_compile(sc_ctx *c, const sc_node *at, const char *text, int allow_t, sc_expr *e);
/* The same with a symbol table: t and named variables mapped to slots of x (expr.h). */
int sc_expr_compile_sym(sc_ctx *c, const sc_node *at, const char *text, const sc_symtab *sym,
                        sc_expr *e);
/* Read a number or expression of t from a node. */
int sc_expr_read(sc_ctx *c, const sc_node *n, sc_expr *e);
/* sc_expr_read after the checks of read.c (a scalar, not YAML's .inf or .nan): what the
 * parsers call for a function of t. */
int sc_expr_node(sc_ctx *c, const sc_node *n, sc_expr *e);
void sc_expr_free(sc_expr *e);
/* f[0..2] at t: value and the two time derivatives (constants: value, 0, 0). Returns 0, or
 * -1 when one is not finite (or the expression needs variables). */
int sc_expr_eval(const sc_expr *e, double t, double f[3]);
/* An ap_time_fn with user = sc_expr *. */
int sc_expr_time_fn(double t, double f[3], void *user);
/* AP_OK when the expression's jet from these seeds is finite up to `order` (0: value, 2:
 * both derivatives); otherwise a message at its node: "'log(t-1)' is not finite at t = 0:
 * log(-1) = nan (column 1 of the expression)". */
int sc_expr_check_jet(sc_ctx *c, const sc_expr *e, const sc_jet *t, const sc_jet *x,
                      int order);
/* The same for an expression of t at time t with both derivatives (expressions that use
 * variables are skipped: they need the state). */
int sc_expr_check(sc_ctx *c, const sc_expr *e, double t);

/* ---- parameters, includes and parts (params.c, include.c, parts.c) ---------------------- */

/* The parameters of a scene: names and values in file order, evaluated once at load. */
typedef struct sc_params sc_params;
/* Read root's parameters: section (cycles and unknown names refused at their node) and point
 * every node of the tree at the table; *out is NULL when there is none. */
/* The symbol table's lookup of expressions naming parameters (expr.c uses it). */
void sc_params_symtab(const sc_params *p, sc_symtab *sym);
int sc_params_read(sc_ctx *c, sc_node *root, sc_params **out);
void sc_params_free(sc_params *p);
int sc_params_count(const sc_params *p);
const char *sc_params_name(const sc_params *p, int i);
double sc_params_value(const sc_params *p, int i);
/* Strings that nodes point to (file names, instance notes): owned here, freed with the scene. */
typedef struct sc_strings {
  int n, cap;
  char **s;
} sc_strings;
const char *sc_strings_add(sc_strings *pool, const char *text);
void sc_strings_free(sc_strings *pool);
/* Expand include: (file names relative to dir, the including file's folder) into root. */
int sc_include_expand(sc_ctx *c, sc_node *root, const char *file, sc_strings *pool);
/* Expand instances: of parts: into the sections of root. */
int sc_parts_expand(sc_ctx *c, sc_node *root, sc_strings *pool);

/* ---- the parsed scene (parse.c, parse_run.c) ------------------------------------------- */

typedef struct sc_body {
  const char *name;
  const sc_node *node;
  ap_body_def def;
  int uniform;             /* inertia from the shape */
  ap_scene_visual visual;  /* drawn only (parse_visual.c); kind AP_VISUAL_NONE by default */
} sc_body;

/* bodies: NAME: visual: (parse_visual.c). */
int sc_parse_visual(sc_ctx *c, const sc_node *n, ap_scene_visual *v);

/* Initial state of one joint in people's coordinates (init.c converts). */
typedef struct sc_init {
  const sc_node *node;     /* the joint's entry under initial:, or NULL */
  double pos[3];           /* x y z, or angle / position in pos[0] */
  int pos_given[3];
  double vel[3];           /* vx vy vz, or rate in vel[0] */
  int vel_given[3];
  int orient;              /* 0 none, 1 quat, 2 zxz (heading tilt spin), 3 zyx (yaw pitch roll) */
  double quat[4];
  double euler[3];
  int ang;                 /* 0 none, 1 omega (parent axes), 2 omega_body, 3 Euler rates */
  double omega[3];
  double rates[3];
} sc_init;

typedef struct sc_joint {
  const char *name;
  const sc_node *node;
  ap_joint_def def;
  sc_expr drive[3];
  sc_init init;
} sc_joint;

typedef struct sc_ground {
  ap_ground_motion def;
  sc_expr omega, vel[2];
  sc_expr height;          /* kind: height_field: h(x, y) (heightfield.c) */
} sc_ground;

typedef struct sc_con {
  const char *name;
  const sc_node *node;
  ap_constraint_def def;
  sc_ground ground;
  sc_expr value;           /* prescribed speed */
} sc_con;

typedef struct sc_eff {
  const char *name;
  const sc_node *node;
  ap_effect_def def;
  sc_expr force[3], torque[3];
  int timed;               /* some component depends on t: use the wrench callback */
  sc_expr value;           /* joint_torque, joint_force: the value; motor: the set-point */
  int is_torque;           /* written as joint_torque (an AP_EFFECT_JOINT_FORCE) */
} sc_eff;

/* Output channels (bit mask). */
enum {
  SC_OUT_COORDS = 1 << 0,
  SC_OUT_SPEEDS = 1 << 1,
  SC_OUT_ANGLES = 1 << 2,
  SC_OUT_COM = 1 << 3,
  SC_OUT_CONTACTS = 1 << 4,
  SC_OUT_ENERGY = 1 << 5,
  SC_OUT_RESIDUAL = 1 << 6,
  SC_OUT_REACTIONS = 1 << 7,
  SC_OUT_CONTACT_FORCES = 1 << 8,
  SC_OUT_POSES = 1 << 9,
  SC_OUT_DRIVEN = 1 << 10
};
#define SC_OUT_NAMES                                                                     \
  { "coordinates", "speeds", "angles", "com", "contacts", "energy", "residual", "reactions", \
    "contact_forces", "poses", "driven", NULL }

typedef struct sc_scene {
  char *file;
  sc_node *root;
  const char *name;
  int nb, nj, nc, ne;
  sc_body *bodies;
  sc_joint *joints;
  sc_con *cons;
  sc_eff *effs;
  sc_ground ground;        /* default ground motion (top-level ground:) */
  const sc_node *ground_node;
  ap_scene_run run;
  char method[32];
  unsigned channels;
  double init_tol;         /* relative speed correction above which the state is refused */
  int path;                /* simulation.path (ap_path): auto, dense or tree */
  int compile;             /* simulation.compile (ap_compile_mode), -1 when not given */
  int nev;
  struct sc_event *events; /* the events: section and the bodies' collide: keys (events.c) */
  int nkink, nsat;
  struct sc_kink *kinks;   /* kinks of its expressions: implicit events (events.c) */
  struct sc_sat *sats;     /* saturation switching of its motors: implicit events too */
  sc_params *params;       /* the parameters: section (params.c), or NULL */
  sc_strings strings;      /* file names and instance notes the tree's nodes point to */
  int nnamed;
  struct sc_named *named;  /* named output channels, NAME: EXPRESSION (channels.c) */
} sc_scene;

int sc_parse_scene(sc_ctx *c, sc_scene *s);
/* Events (events.c): the events: section and collide: keys of bodies, read after the rest;
 * bound to the model once it is built; freed with the scene. */
int sc_parse_events(sc_ctx *c, sc_scene *s);
int sc_events_bind(sc_ctx *c, sc_scene *s, const ap_model *m);
void sc_events_free(sc_scene *s);
int sc_parse_con_eff(sc_ctx *c, sc_scene *s);
/* Joint effects (parse_act.c): the scene kinds joint_torque, joint_force, motor. */
enum { SC_EFF_TORQUE = 0, SC_EFF_FORCE = 1, SC_EFF_MOTOR = 2 };
int sc_parse_joint_effect(sc_ctx *c, sc_scene *s, const sc_node *n, sc_eff *e, int which);
/* A value node into e and the definition: a number (d->value), an expression of t
 * (d->value_fn) or of the state too (d->state_fn and d->inputs); the caller sets user = e. */
int sc_read_value(sc_ctx *c, sc_scene *s, const sc_node *v, sc_expr *e, ap_effect_def *d);

/* Names of the state in expressions (state.c): JOINT.NAME (and BODY.NAME) for every joint
 * coordinate and speed; name i is slot i of an expression's variables. */
typedef struct sc_state_names {
  int count;
  char **names;            /* count names, then NULL */
  ap_state_input *refs;    /* what name i reads */
  int *driven;             /* 1: name i is a driven coordinate or speed (not in the state) */
} sc_state_names;
int sc_state_names_build(const sc_scene *s, sc_state_names *t);
void sc_state_names_free(sc_state_names *t);
/* Bind e, compiled against the whole table t, to the names it reads: driven names refused
 * (a located message at v), then recompiled against just those, in the order of inputs
 * (at most AP_STATE_MAX_INPUTS). */
int sc_bind_state(sc_ctx *c, const sc_node *v, const sc_state_names *t, sc_expr *e,
                  ap_state_input *inputs, int *ninputs);
/* Global index in q (or v, for a speed) of a state input (never a driven one). */
int sc_state_index(const sc_scene *s, const ap_model *m, const ap_state_input *in);
/* The ap_state_fn of a scene expression of the state (user = its sc_expr). */
int sc_state_fn(const ap_state_args *a, double *f, double *df, void *user);
/* Every expression of the state finite at (t, q, v); else a message at its node. */
int sc_check_state_exprs(sc_ctx *c, const sc_scene *s, const ap_model *m, double t,
                         const double *q, const double *v);
/* Body quantities in expressions (expr_body.c): BODY.x ... BODY.wz appended to t (names it
 * has already are kept); does any of in[nin] read one; the inputs x at (q, v), body quantities
 * from d's kinematics at that state (index: global q or v index of the others); the
 * kinematics of (t, q, v) into d (ap_body_eval). */
int sc_state_names_add_bodies(const sc_scene *s, sc_state_names *t);
int sc_inputs_read_bodies(const ap_state_input *in, int nin);
int sc_state_gather(const ap_model *m, const ap_data *d, const ap_state_input *in,
                    const int *index, int nin, const double *q, const double *v, double *x);
int sc_state_at(const ap_model *m, ap_data *d, double t, const double *q, const double *v);
int sc_parse_ground(sc_ctx *c, const sc_node *n, sc_ground *g);
/* friction and unilateral of a rolling constraint (parse_friction.c). */
int sc_parse_friction(sc_ctx *c, const sc_node *n, ap_constraint_def *d);
/* 1 when constraint k (a scene's s) has contact modes (parse_friction.c). */
int sc_con_has_modes(const sc_con *k);
int sc_scene_has_modes(const sc_scene *s);
/* The kind of constraint k for listings (kinds by ap_constraint_kind), with its modes. */
const char *sc_con_kind_text(const sc_con *k, const char *const *kinds);
void sc_ground_bind(sc_ground *g);
/* A height-field ground (heightfield.c): its `z` expression of x and y read at n into g (and
 * g->def.height_fn set); the copy of one (inherited by a constraint); the height function. */
int sc_parse_height(sc_ctx *c, const sc_node *n, sc_ground *g);
int sc_height_copy(sc_ctx *c, const sc_ground *from, sc_ground *to);
int sc_height_fn(double x, double y, double h[6], void *user);
int sc_parse_run(sc_ctx *c, sc_scene *s);
/* The keys of initial: for a joint of this kind (NULL-terminated). */
const char *const *sc_init_keys(ap_joint_kind kind);
/* An initial-state map n of joint j giving a driven coordinate: the error at its value. */
int sc_check_driven(sc_ctx *c, const sc_node *n, const sc_joint *j);
/* The linearize: section (linearize.c): keys, types and joint names checked at load. */
int sc_parse_linearize(sc_ctx *c, const sc_scene *s);
/* "FILE:LINE:COL: linearize.LIST.I" (or the --set that gave it), the location of entry i of
 * the section's name list; 0 when there is no such entry. */
int sc_lin_entry_at(const ap_scene *sc, const char *list, int i, char *buf, size_t len);
void sc_scene_clear(sc_scene *s);
int sc_find_body(const sc_scene *s, const char *name);   /* -1 if none */
int sc_find_joint(const sc_scene *s, const char *name);  /* -1 if none */
/* Read a body reference ("ground" allowed when ground_ok): *id = index or AP_GROUND. */
int sc_get_body_ref(sc_ctx *c, const sc_scene *s, const sc_node *map, const char *key,
                    int ground_ok, int *id);

/* Coordinate, speed and drivable names of a joint kind in scenes (docs/scenes.md). */
const char *sc_joint_kind_name(ap_joint_kind kind);
int sc_joint_drivable(ap_joint_kind kind, const char *coord);   /* index or -1 */
int sc_joint_speed(ap_joint_kind kind, const char *speed);      /* index or -1 */

/* ---- outputs (output.c) --------------------------------------------------------------- */

typedef struct sc_out {
  int ncols;
  char **cols;             /* column names; cols[0] = "t" */
  double *angles;          /* (3 nj) last Euler angles, for unwrapping */
  double E0;               /* energy at the first row */
  long rows;               /* rows evaluated */
} sc_out;

int sc_out_names(sc_out *o, const sc_scene *s, const ap_model *m);
void sc_out_free(sc_out *o);
/* Fill row (o->ncols values) at the simulation's state, using d as scratch. */
int sc_out_row(sc_out *o, const sc_scene *s, const ap_model *m, ap_data *d, ap_sim *sim,
               double *row);
int sc_out_energy(const ap_model *m, ap_data *d, double *T, double *V);
/* Named channels and the driven channel (channels.c): read a mapping item of
 * output.channels; free them; the number of their columns, the name of column i (buf: room
 * for a driven column's name), and their values at the data's (t, q, v) into row (returns the
 * count written, or a negative status). */
int sc_parse_named_channels(sc_ctx *c, sc_scene *s, const sc_node *map);
void sc_named_free(sc_scene *s);
int sc_named_count(const sc_scene *s, const ap_model *m);
const char *sc_named_column(const sc_scene *s, int i, char *buf, size_t len);
int sc_named_values(const sc_scene *s, const ap_model *m, ap_data *d, double *row);
/* The scene's own data, which output rows, ap_scene_energy and ap_scene_residual evaluate in:
 * its counters (cnt.energy, cnt.position) show which optional outputs were computed. */
const ap_data *sc_scene_output_data(const ap_scene *sc);
/* The parsed scene behind an ap_scene (scene_run.c evaluates rows of it per run). */
const sc_scene *sc_scene_parsed(const ap_scene *sc);

/* ---- building and initial state (build.c, init.c) ------------------------------------- */

int sc_build(sc_ctx *c, sc_scene *s, ap_model **out);
int sc_initial_state(sc_ctx *c, const sc_scene *s, const ap_model *m, double *q0, double *v0,
                     char *report, size_t report_len);

/* ---- checks at a time (expr_scene.c) ------------------------------------------------------ */

/* Every expression of t in the scene, with both derivatives, at t: AP_OK, or a message at the
 * first one (in file order) that is not finite. Reads the scene only. */
int sc_check_exprs(sc_ctx *c, const sc_scene *s, double t);
/* The equations of motion at (t0, q0, v0): AP_OK, or a located message when they are not
 * finite there (speeds that overflow are blamed on the largest number under initial:). */
int sc_check_start(sc_ctx *c, const sc_scene *s, const ap_model *m, const double *q0,
                   const double *v0);

/* Euler angles (rad) to a quaternion [w x y z]: zxz = Rz(a) Rx(b) Rz(c), zyx = Rz(a) Ry(b)
 * Rx(c). */
void sc_euler_to_quat(int zyx, const double e[3], double q[4]);
/* Angular velocity (parent axes) from Euler angles and their rates. */
void sc_euler_rates_to_omega(int zyx, const double e[3], const double rates[3], double w[3]);
/* Z-X-Z angles (heading, tilt, spin) of a rotation. */
void sc_quat_to_zxz(const double q[4], double e[3]);

/* The inputs: section (inputs.c): checked against the model at load; its names (into the
 * tree, NULL-terminated, freed by the caller; NULL without the section, *count -1 when out
 * of memory). */
int sc_inputs_check(sc_ctx *c, const sc_scene *s, const ap_model *m);
const char **sc_input_names(const sc_scene *s, int *count);

#endif
