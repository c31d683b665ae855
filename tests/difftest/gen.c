/* Random valid models for the differential tester (docs/testing.md, "Modes must agree").
 *
 * From a seed (the tests' xorshift64*, tests/testrand.h) it builds a tree of up to 6 bodies
 * with every joint kind of the scene language (fixed, revolute, prismatic, planar, ball, free,
 * plane_contact), random frames, masses, inertias (principal moments from three positive
 * second moments, so the triangle inequality holds, turned by a random rotation) and shapes;
 * constraints (rolling and knife edges on plane-contact bodies, knife edges on any body, wheel
 * contacts of free spheres and of a planar chassis with two wheels on one axle, prescribed
 * speeds, loop closures, and rows made redundant on purpose), effects (gravity, springs,
 * dampers, joint torques, motors, applied forces), sometimes a moving ground, and an initial
 * state per joint that the library makes consistent. Loop closures are placed where the
 * bodies are at the initial state: a first scene without them is loaded and its kinematics
 * read (ap_body_get_state), so the closure holds there. Numbers are written with 4 digits:
 * a model is its scene text. */
#include "gen.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "appell/appell.h"
#include "testrand.h"

#define PI 3.14159265358979323846
#define PRINTF(a, b) __attribute__((format(printf, a, b)))

static double ur(uint64_t *s, double a, double b) { return a + (b - a) * ap_test_urand(s); }
static int ui(uint64_t *s, int n) { return (int)(ap_test_urand(s) * n); }
static int chance(uint64_t *s, double p) { return ap_test_urand(s) < p; }

/* Append printf output to buf (total len); cat: to a DT_TXT fragment. */
PRINTF(3, 4) static void put(char *buf, size_t len, const char *fmt, ...) {
  size_t used = strlen(buf);
  if (used + 1 >= len) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf + used, len - used, fmt, ap);
  va_end(ap);
}
#define cat(buf, ...) put(buf, DT_TXT, __VA_ARGS__)

static void vec3(char *buf, const char *key, double x, double y, double z) {
  cat(buf, "%s: [%.4g, %.4g, %.4g]", key, x, y, z);
}

/* A random unit vector. */
static void unit(uint64_t *s, double u[3]) {
  double n;
  do {
    for (int i = 0; i < 3; i++) u[i] = ur(s, -1, 1);
    n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  } while (n < 0.2 || n > 1.0);
  for (int i = 0; i < 3; i++) u[i] /= n;
}

/* ---- bodies ----------------------------------------------------------------------------- */

static int solid(int shape) { return shape != DT_SH_NONE; }

static void shape_text(uint64_t *s, dt_body *b) {
  double r = ur(s, 0.05, 0.3);
  switch (b->shape) {
    case DT_SH_SPHERE: cat(b->body, ", shape: {kind: sphere, radius: %.4g}", r); break;
    case DT_SH_DISK: cat(b->body, ", shape: {kind: disk, radius: %.4g}", r); break;
    case DT_SH_TORUS:
      cat(b->body, ", shape: {kind: torus, radius: %.4g, tube: %.4g}", r, r * ur(s, 0.1, 0.5));
      break;
    case DT_SH_ELLIPSOID:
      cat(b->body, ", shape: {kind: ellipsoid, semi_axes: [%.4g, %.4g, %.4g]}", r,
          ur(s, 0.05, 0.3), ur(s, 0.05, 0.3));
      break;
    default: break;
  }
}

/* Inertia about the centre of mass: R diag(y+z, x+z, x+y) R^T, x, y, z > 0 (triangle
 * inequality by construction), R a rotation by a random angle about a random axis. */
static void inertia_text(uint64_t *s, dt_body *b, double mass) {
  double x = ur(s, 0.1, 1), y = ur(s, 0.1, 1), z = ur(s, 0.1, 1), L2 = mass * ur(s, 0.005, 0.05);
  double D[3] = {(y + z) * L2, (x + z) * L2, (x + y) * L2}, ax[3], q[4], R[9], I[9];
  unit(s, ax);
  ap_quat_from_axis_angle(ax, ur(s, -PI, PI), q);
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      I[i + 3 * j] = 0;
      for (int c = 0; c < 3; c++) I[i + 3 * j] += R[i + 3 * c] * D[c] * R[j + 3 * c];
    }
  if (chance(s, 0.3))
    cat(b->body, ", inertia: [%.4g, %.4g, %.4g]", D[0], D[1], D[2]);
  else
    cat(b->body, ", inertia: [%.6g, %.6g, %.6g, %.6g, %.6g, %.6g]", I[0], I[4], I[8], I[3], I[6],
        I[7]);
}

static void body_text(uint64_t *s, dt_body *b) {
  double mass = ur(s, 0.2, 3);
  snprintf(b->body, DT_TXT, "{mass: %.4g", mass);
  shape_text(s, b);
  if (solid(b->shape) && chance(s, 0.5)) {
    cat(b->body, ", inertia: uniform}");
    return;
  }
  if (chance(s, 0.6)) {
    cat(b->body, ", ");
    vec3(b->body, "com", ur(s, -0.1, 0.1), ur(s, -0.1, 0.1), ur(s, -0.1, 0.1));
  }
  inertia_text(s, b, mass);
  cat(b->body, "}");
}

/* ---- joints and initial states ---------------------------------------------------------- */

static void frame_text(uint64_t *s, char *buf, const char *key, double span, double zlo,
                       double zhi) {
  cat(buf, ", %s: {", key);
  vec3(buf, "pos", ur(s, -span, span), ur(s, -span, span), ur(s, zlo, zhi));
  if (chance(s, 0.6)) {
    double ax[3];
    unit(s, ax);
    cat(buf, ", axis: [%.4g, %.4g, %.4g], angle: %.4g", ax[0], ax[1], ax[2], ur(s, -3, 3));
  }
  cat(buf, "}");
}

static void axis_text(uint64_t *s, char *buf) {
  static const char *const named[] = {"x", "y", "z", "-x", "-y", "-z"};
  if (chance(s, 0.6)) {
    cat(buf, ", axis: %s", named[ui(s, 6)]);
    return;
  }
  double ax[3];
  unit(s, ax);
  cat(buf, ", ");
  vec3(buf, "axis", ax[0], ax[1], ax[2]);
}

/* Orientation and angular velocity of a ball, free or plane-contact joint; tilt_lo keeps a
 * disk or torus off lying flat. */
static void orient_text(uint64_t *s, char *buf, double tilt_lo) {
  if (chance(s, 0.5))
    cat(buf, "heading: %.4g, tilt: %.4g, spin: %.4g", ur(s, -3, 3), ur(s, tilt_lo, PI - tilt_lo),
        ur(s, -3, 3));
  else if (tilt_lo > 0)
    cat(buf, "heading: %.4g, tilt: %.4g", ur(s, -3, 3), ur(s, tilt_lo, PI - tilt_lo));
  else
    cat(buf, "yaw: %.4g, pitch: %.4g, roll: %.4g", ur(s, -3, 3), ur(s, -1.5, 1.5), ur(s, -3, 3));
  if (chance(s, 0.5)) {
    cat(buf, ", ");
    vec3(buf, chance(s, 0.5) ? "omega" : "omega_body", ur(s, -3, 3), ur(s, -3, 3), ur(s, -3, 3));
  } else if (chance(s, 0.7) && strstr(buf, "heading:")) {
    cat(buf, ", spin_rate: %.4g, heading_rate: %.4g", ur(s, -6, 6), ur(s, -2, 2));
  }
}

static void init_text(uint64_t *s, dt_body *b) {
  char *t = b->init;
  t[0] = 0;
  if (b->driven || b->kind == DT_FIXED || (b->kind != DT_PLANE && chance(s, 0.1))) return;
  cat(t, "{");
  switch (b->kind) {
    case DT_REVOLUTE: cat(t, "angle: %.4g, rate: %.4g", ur(s, -3, 3), ur(s, -3, 3)); break;
    case DT_PRISMATIC: cat(t, "position: %.4g, rate: %.4g", ur(s, -.2, .2), ur(s, -1, 1)); break;
    case DT_PLANAR:
      cat(t, "x: %.4g, y: %.4g, heading: %.4g, vx: %.4g, vy: %.4g, heading_rate: %.4g",
          ur(s, -.5, .5), ur(s, -.5, .5), ur(s, -3, 3), ur(s, -1, 1), ur(s, -1, 1), ur(s, -3, 3));
      break;
    case DT_BALL: orient_text(s, t, 0); break;
    case DT_FREE:
      cat(t, "x: %.4g, y: %.4g, z: %.4g, vx: %.4g, vy: %.4g, vz: %.4g, ", ur(s, -.5, .5),
          ur(s, -.5, .5), ur(s, -.5, .5), ur(s, -1, 1), ur(s, -1, 1), ur(s, -1, 1));
      orient_text(s, t, b->shape == DT_SH_DISK || b->shape == DT_SH_TORUS ? 0.5 : 0);
      break;
    case DT_PLANE:
      cat(t, "x: %.4g, y: %.4g, ", ur(s, -.5, .5), ur(s, -.5, .5));
      orient_text(s, t, b->shape == DT_SH_DISK || b->shape == DT_SH_TORUS ? 0.5 : 0);
      break;
    default: break;
  }
  cat(t, "}");
  if (!strcmp(t, "{}")) t[0] = 0;
}

static const char *const kind_name[DT_NKIND] = {"fixed", "revolute", "prismatic", "planar",
                                                "ball", "free", "plane_contact"};

/* Pick from weights w[DT_NKIND]. */
static int pick(uint64_t *s, const double *w) {
  double tot = 0, x;
  for (int i = 0; i < DT_NKIND; i++) tot += w[i];
  x = ur(s, 0, tot);
  for (int i = 0; i < DT_NKIND; i++)
    if ((x -= w[i]) < 0) return i;
  return DT_REVOLUTE;
}

static void joint_text(uint64_t *s, dt_model *m, int i) {
  static const double w_ground[DT_NKIND] = {0.2, 2, 1, 2, 1.5, 1.5, 2.5};
  static const double w_body[DT_NKIND] = {0.6, 3, 1.5, 1, 2, 0.7, 0};
  dt_body *b = &m->b[i];
  b->parent = i == 0 || chance(s, 0.35) ? -1 : ui(s, i);
  b->kind = pick(s, b->parent < 0 ? w_ground : w_body);
  if (b->kind == DT_PLANE) b->shape = DT_SH_SPHERE + ui(s, 4);
  else b->shape = chance(s, 0.7) ? DT_SH_NONE : (chance(s, 0.5) ? DT_SH_SPHERE : DT_SH_DISK);
  char *j = b->joint;
  snprintf(j, DT_TXT, "{kind: %s", kind_name[b->kind]);
  if (b->kind != DT_PLANE) {
    if (b->parent >= 0) cat(j, ", parent: b%d", b->parent);
    if (chance(s, 0.8)) frame_text(s, j, "parent_frame", b->parent < 0 ? 0.5 : 0.3, -0.3, 0.6);
    if (chance(s, 0.3)) frame_text(s, j, "child_frame", 0.2, -0.2, 0.2);
  }
  if (b->kind == DT_REVOLUTE || b->kind == DT_PRISMATIC) {
    axis_text(s, j);
    if (chance(s, 0.1)) {
      b->driven = 1;
      if (b->kind == DT_REVOLUTE) cat(j, ", drive: {angle: \"%.3g*sin(%.3g*t)\"}", ur(s, .1, 1),
                                      ur(s, 1, 4));
      else cat(j, ", drive: {position: \"%.3g*sin(%.3g*t)\"}", ur(s, .05, .2), ur(s, 1, 4));
    }
  }
  cat(j, "}");
}

/* ---- constraints and effects ------------------------------------------------------------ */

static dt_item *add_con(dt_model *m, int r0, int r1) {
  if (m->nc >= DT_MAXC) return NULL;
  dt_item *c = &m->c[m->nc++];
  c->live = 1, c->refs[0] = r0, c->refs[1] = r1, c->text[0] = 0;
  return c;
}

static dt_item *add_eff(dt_model *m, int r0, int r1) {
  if (m->ne >= DT_MAXE) return NULL;
  dt_item *e = &m->e[m->ne++];
  e->live = 1, e->refs[0] = r0, e->refs[1] = r1, e->text[0] = 0;
  return e;
}

static int has_speed(const dt_body *b) { return b->kind != DT_FIXED && !b->driven; }
static int is_wheel(const dt_body *b) { return b->shape == DT_SH_DISK || b->shape == DT_SH_TORUS; }

static void body_constraints(uint64_t *s, dt_model *m, int i) {
  dt_body *b = &m->b[i];
  dt_item *c;
  if (b->kind == DT_PLANE) {
    int roll = chance(s, 0.6);
    if (roll && (c = add_con(m, i, -1)))
      snprintf(c->text, DT_TXT, "{kind: rolling, body: b%d%s}", i,
               chance(s, 0.15) ? ", no_spin: true" : "");
    if (is_wheel(b) && (!roll || chance(s, 0.2)) && (c = add_con(m, i, -1)))
      snprintf(c->text, DT_TXT, "{kind: knife_edge, body: b%d}", i);   /* redundant with roll */
  } else if (b->kind == DT_FREE && b->shape == DT_SH_SPHERE && chance(s, 0.5)) {
    if ((c = add_con(m, i, -1))) snprintf(c->text, DT_TXT, "{kind: rolling, body: b%d}", i);
    /* a wheel contact: on one body, the tree path takes it unless the free joint hangs from
     * another body (lib/model/contact.c) */
    if (b->parent >= 0) m->expect_tree = 0;
  } else if (has_speed(b) && chance(s, b->kind == DT_PLANAR ? 0.4 : 0.1) &&
             (c = add_con(m, i, -1))) {
    double a = ur(s, -3, 3);
    snprintf(c->text, DT_TXT, "{kind: knife_edge, body: b%d, ", i);
    vec3(c->text, "point", ur(s, -.2, .2), ur(s, -.2, .2),
         b->kind == DT_PLANAR ? 0 : ur(s, -.2, .2));
    cat(c->text, ", ");
    vec3(c->text, "direction", cos(a), sin(a), b->kind == DT_PLANAR ? 0 : ur(s, -1, 1));
    cat(c->text, "}");
  }
  if ((b->kind == DT_REVOLUTE || b->kind == DT_PRISMATIC) && !b->driven && chance(s, 0.15)) {
    char value[48];
    if (chance(s, 0.5)) snprintf(value, sizeof value, "%.4g", ur(s, -2, 2));
    else snprintf(value, sizeof value, "\"%.3g*sin(%.3g*t)\"", ur(s, .2, 2), ur(s, 1, 3));
    int copies = chance(s, 0.3) ? 2 : 1;   /* the copy is redundant on purpose */
    for (int k = 0; k < copies; k++)
      if ((c = add_con(m, i, -1)))
        snprintf(c->text, DT_TXT, "{kind: prescribed_speed, joint: b%d, speed: rate, value: %s}",
                 i, value);
  }
}

static void effects(uint64_t *s, dt_model *m) {
  dt_item *e;
  if (chance(s, 0.8) && (e = add_eff(m, -1, -1))) {
    if (chance(s, 0.8)) snprintf(e->text, DT_TXT, "{kind: gravity}");
    else snprintf(e->text, DT_TXT, "{kind: gravity, g: [%.4g, %.4g, -9.81]}", ur(s, -3, 3),
                  ur(s, -3, 3));
  }
  int nb = m->nb;
  if (chance(s, 0.4)) {
    int a = ui(s, nb), g2 = chance(s, 0.5) ? -1 : ui(s, nb);
    if (g2 == a) g2 = -1;
    if ((e = add_eff(m, a, g2))) {
      snprintf(e->text, DT_TXT, "{kind: spring, body: b%d, ", a);
      vec3(e->text, "point", ur(s, -.1, .1), ur(s, -.1, .1), ur(s, -.1, .1));
      if (g2 >= 0) cat(e->text, ", body2: b%d", g2);
      cat(e->text, ", ");
      vec3(e->text, "point2", ur(s, -.3, .3), ur(s, -.3, .3), ur(s, -.3, .3));
      cat(e->text, ", stiffness: %.4g", ur(s, 1, 50));
      if (chance(s, 0.4)) cat(e->text, ", damping: %.4g", ur(s, 0.05, 1));
      if (chance(s, 0.4)) cat(e->text, ", rest_length: %.4g", ur(s, 0.05, 0.3));
      cat(e->text, "}");
    }
  }
  for (int tries = 0; tries < 3; tries++) {
    int j = ui(s, nb);
    const dt_body *b = &m->b[j];
    if (!has_speed(b) || !chance(s, 0.25)) continue;
    int r = b->kind == DT_REVOLUTE;
    double x = ap_test_urand(s);
    if (!(e = add_eff(m, j, -1))) break;
    if (x < 0.3) snprintf(e->text, DT_TXT, "{kind: joint_damping, joint: b%d, damping: %.4g}",
                          j, ur(s, 0.01, 0.5));
    else if (r && x < 0.55)
      snprintf(e->text, DT_TXT, "{kind: joint_torque, joint: b%d, torque: \"-%.3g*b%d.angle - "
               "%.3g*b%d.rate\"}", j, ur(s, .1, 3), j, ur(s, 0, .2), j);
    else if (r && x < 0.75)
      snprintf(e->text, DT_TXT, "{kind: joint_torque, joint: b%d, torque: \"%.3g*sin(%.3g*t)\"}",
               j, ur(s, -.5, .5), ur(s, 1, 4));
    else if (r && x < 0.9)
      snprintf(e->text, DT_TXT, "{kind: motor, joint: b%d, rate: %.4g, kd: %.4g}", j,
               ur(s, -3, 3), ur(s, 0.05, 0.5));
    else
      snprintf(e->text, DT_TXT, "{kind: applied, body: b%d, point: [%.4g, 0, 0], force: [0, "
               "\"%.3g*sin(t)\", 0]}", j, ur(s, -.1, .1), ur(s, -1, 1));
  }
}

/* A planar chassis at the wheels' height with two wheels on one axle, each rolling (their
 * contact rows and one sideways row are redundant on purpose), maybe one wheel's rate held. */
static void vehicle(uint64_t *s, dt_model *m) {
  double r = ur(s, 0.08, 0.2), half = ur(s, 0.15, 0.35), xw = ur(s, -0.2, 0.2);
  dt_body *c = &m->b[m->nb];
  c->live = 1, c->kind = DT_PLANAR, c->parent = -1, c->shape = DT_SH_NONE;
  body_text(s, c);
  snprintf(c->joint, DT_TXT, "{kind: planar, parent_frame: {pos: [0, 0, %.4g]}}", r);
  snprintf(c->init, DT_TXT, "{vx: %.4g, heading_rate: %.4g}", ur(s, -1, 1), ur(s, -1, 1));
  int ic = m->nb++;
  for (int side = 0; side < 2; side++) {
    dt_body *w = &m->b[m->nb];
    w->live = 1, w->kind = DT_REVOLUTE, w->parent = ic, w->shape = DT_SH_DISK;
    snprintf(w->body, DT_TXT, "{mass: %.4g, shape: {kind: disk, radius: %.4g}, inertia: uniform}",
             ur(s, 0.2, 1), r);
    snprintf(w->joint, DT_TXT, "{kind: revolute, parent: b%d, parent_frame: {pos: [%.4g, %.4g, "
             "0], axis: x, angle: -90*deg}}", ic, xw, side ? -half : half);
    w->init[0] = 0;
    dt_item *k = add_con(m, m->nb, -1);
    if (k) snprintf(k->text, DT_TXT, "{kind: rolling, body: b%d}", m->nb);
    m->nb++;
  }
  dt_item *k;
  if (chance(s, 0.3) && (k = add_con(m, m->nb - 1, -1)))
    snprintf(k->text, DT_TXT, "{kind: prescribed_speed, joint: b%d, speed: rate, value: %.4g}",
             m->nb - 1, ur(s, -5, 5));
}

/* A loop closure at the bodies' initial positions (closure.c). */
void dt_add_closure(uint64_t *s, dt_model *m);
/* Friction, lift-off and restitution on some rolling contacts (gen_contact.c). */
void dt_add_contact_modes(uint64_t seed, dt_model *m);

static int has_rolling(const dt_model *m) {
  for (int c = 0; c < m->nc; c++)
    if (strstr(m->c[c].text, "rolling") || strstr(m->c[c].text, "knife_edge")) return 1;
  return 0;
}

int dt_gen_contacts;

void dt_generate(uint64_t seed, dt_model *m) {
  memset(m, 0, sizeof *m);
  uint64_t st = seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull, *s = &st;
  for (int i = 0; i < 4; i++) ap_test_urand(s);
  m->seed = seed, m->expect_tree = 1, m->t_end = 0.5;
  if (chance(s, 0.2)) vehicle(s, m);
  int first = m->nb, extra = 1 + ui(s, m->nb ? 3 : 4);
  for (int k = 0; k < extra; k++) {
    dt_body *b = &m->b[m->nb];
    b->live = 1;
    joint_text(s, m, m->nb);
    body_text(s, b);
    init_text(s, b);
    m->nb++;
  }
  for (int i = first; i < m->nb; i++) body_constraints(s, m, i);
  effects(s, m);
  if (has_rolling(m) && chance(s, 0.15)) {
    if (chance(s, 0.5)) snprintf(m->ground, sizeof m->ground, "{kind: turntable, omega: %.4g}",
                                 ur(s, -1, 1));
    else snprintf(m->ground, sizeof m->ground, "{kind: translating, velocity: [%.4g, "
                  "\"%.3g*sin(t)\"]}", ur(s, -.5, .5), ur(s, -.5, .5));
  }
  if (dt_gen_contacts) dt_add_contact_modes(seed, m);   /* a stream of its own: gen_contact.c */
  if (chance(s, 0.25)) dt_add_closure(s, m);
}

int dt_live_bodies(const dt_model *m) {
  int n = 0;
  for (int i = 0; i < m->nb; i++) n += m->b[i].live;
  return n;
}

void dt_drop_body(dt_model *m, int i) {
  m->b[i].live = 0;
  for (int j = i + 1; j < m->nb; j++)   /* parents come first */
    if (m->b[j].parent >= 0 && !m->b[m->b[j].parent].live) m->b[j].live = 0;
  dt_item *lists[2] = {m->c, m->e};
  int counts[2] = {m->nc, m->ne};
  for (int l = 0; l < 2; l++)
    for (int c = 0; c < counts[l]; c++)
      for (int r = 0; r < 2; r++)
        if (lists[l][c].refs[r] >= 0 && !m->b[lists[l][c].refs[r]].live) lists[l][c].live = 0;
}

static void put_items(char *buf, size_t len, const char *section, char prefix,
                      const dt_item *it, int count) {
  int any = 0;
  for (int i = 0; i < count; i++) any |= it[i].live;
  if (!any) return;
  put(buf, len, "%s:\n", section);
  for (int i = 0; i < count; i++)
    if (it[i].live) put(buf, len, "  %c%d: %s\n", prefix, i, it[i].text);
}

void dt_write(const dt_model *m, const char *header, char *buf, size_t len) {
  buf[0] = 0;
  for (const char *h = header; h && *h;) {
    const char *nl = strchr(h, '\n');
    int n = nl ? (int)(nl - h) : (int)strlen(h);
    put(buf, len, "# %.*s\n", n, h);
    h += n + (nl != NULL);
  }
  put(buf, len, "name: dt_%llu\nbodies:\n", (unsigned long long)m->seed);
  for (int i = 0; i < m->nb; i++)
    if (m->b[i].live) put(buf, len, "  b%d: %s\n", i, m->b[i].body);
  put(buf, len, "joints:\n");
  for (int i = 0; i < m->nb; i++)
    if (m->b[i].live) put(buf, len, "  b%d: %s\n", i, m->b[i].joint);
  put_items(buf, len, "constraints", 'c', m->c, m->nc);
  put_items(buf, len, "effects", 'e', m->e, m->ne);
  if (m->ground[0]) put(buf, len, "ground: %s\n", m->ground);
  int any = 0;
  for (int i = 0; i < m->nb; i++) any |= m->b[i].live && m->b[i].init[0];
  if (any) put(buf, len, "initial:\n");
  for (int i = 0; i < m->nb; i++)
    if (m->b[i].live && m->b[i].init[0]) put(buf, len, "  b%d: %s\n", i, m->b[i].init);
  put(buf, len, "simulation: {t_end: %.4g, rtol: 1e-8, atol: 1e-10}\n", m->t_end);
  put(buf, len, "output: {interval: %.4g, channels: [coordinates, speeds, energy, residual]}\n",
      m->t_end / 4);
}
