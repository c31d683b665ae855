/* Body models shared by the tests and the benchmarks (bodysys.h): builders through the public
 * API and state setters. Every builder call is checked; a failure is printed with the
 * builder's message and counted, and the model comes back NULL. */
#include "bodysys.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static int failures = 0;

int bs_failures(void) { return failures; }

static void fail(const char *what, const char *msg) {
  failures++;
  fprintf(stderr, "bodysys: %s: %s\n", what, msg ? msg : "");
}

/* Counts a failed status of a builder call; returns 1 when rc is AP_OK. */
static int ok(ap_builder *b, int rc, const char *what) {
  if (rc == AP_OK) return 1;
  fail(what, b ? ap_builder_message(b) : ap_strerror(rc));
  return 0;
}

static ap_builder *builder(const char *name) {
  ap_builder *b = NULL;
  if (ap_builder_create(name, &b) != AP_OK) fail(name, "cannot create a builder");
  return b;
}

ap_model *bs_compile(ap_builder *b) {
  ap_model *m = NULL;
  if (!b) return NULL;
  if (ap_builder_compile(b, &m) != AP_OK) fail("compile", ap_builder_message(b)), m = NULL;
  ap_builder_free(b);
  return m;
}

/* Compiles b when every step that built it succeeded (good); frees it either way. */
static ap_model *finish(ap_builder *b, int good) {
  if (good) return bs_compile(b);
  ap_builder_free(b);
  return NULL;
}

/* Body d (id 0) on a joint of the given kind to the ground. */
static int root_body(ap_builder *b, const ap_body_def *d, ap_joint_kind kind) {
  ap_joint_def j = ap_joint_def_default();
  j.kind = kind, j.child = 0;
  return ok(b, ap_builder_add_body(b, d, NULL), d->name) &&
         ok(b, ap_builder_add_joint(b, &j, NULL), "joint");
}

/* Uniform gravity (0, 0, -grav). */
static int gravity(ap_builder *b, double grav) {
  ap_effect_def e = ap_effect_def_default();
  e.gravity[2] = -grav;
  return ok(b, ap_builder_add_effect(b, &e, NULL), "gravity");
}

int bs_add_body(ap_builder *b, const char *name, double mass, const double *com,
                const double *Idiag) {
  ap_body_def d = ap_body_def_default();
  int id = -1;
  d.name = name, d.mass = mass;
  if (com) memcpy(d.com, com, sizeof d.com);
  for (int i = 0; i < 3; i++) d.inertia[4 * i] = Idiag[i];
  return ok(b, ap_builder_add_body(b, &d, &id), name) ? id : -1;
}

ap_sim *bs_start(const ap_model *m, ap_mode mode, const char *method, double rtol,
                 double atol, const double *q0, const double *v0) {
  ap_sim_def sd = ap_sim_def_default();
  ap_sim *s = NULL;
  char msg[512] = "";
  sd.mode = mode, sd.method = method, sd.rtol = rtol, sd.atol = atol;
  if (ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg) != AP_OK) {
    fail(m ? ap_model_name(m) : "ap_sim_create", msg);
    return NULL;
  }
  return s;
}

double bs_energy(const ap_model *m, ap_data *d, const double *q, const double *v) {
  double T = 0.0, V = 0.0;
  memcpy(d->q, q, sizeof(double) * (size_t)ap_model_n(m));
  memcpy(d->v, v, sizeof(double) * (size_t)ap_model_k(m));
  int rc = ap_body_energy(m, d, &T, &V);
  if (rc != AP_OK) {
    fail("ap_body_energy", d->msg);
    return NAN;
  }
  return T + V;
}

/* Completes the speeds not marked in given from the constraints at t = 0; d may be NULL. */
static int complete(const ap_model *m, ap_data *d, double *q, const int *given, double *v) {
  ap_data *own = NULL;
  if (!d && ap_data_create(m, &own) != AP_OK) {
    fail("ap_data_create", "cannot create a data struct");
    return AP_ERR_NOMEM;
  }
  ap_data *dd = d ? d : own;
  dd->t = 0.0;
  int rc = ap_body_complete_speeds(m, dd, q, given, v);
  if (rc != AP_OK) fail("ap_body_complete_speeds", dd->msg);
  ap_data_free(own);
  return rc;
}

/* ---- rolling disk ------------------------------------------------------------------------ */

bs_disk bs_disk_default(void) {
  bs_disk p = {1.5, 0.3, 9.81, 1.5 * 0.09 / 4, 1.5 * 0.09 / 2, 0, 0, 0.0};
  return p;
}

ap_model *bs_disk_model(const bs_disk *p) {
  ap_builder *b = builder(p->torus ? "rolling torus" : "rolling disk");
  if (!b) return NULL;
  ap_body_def d = ap_body_def_default();
  d.name = p->torus ? "wheel" : "disk";
  d.shape.kind = p->torus ? AP_SHAPE_TORUS : AP_SHAPE_DISK;
  d.shape.radius = p->r, d.shape.tube = p->torus ? 0.02 : 0.0;
  d.mass = p->m;
  d.inertia[0] = d.inertia[4] = p->A, d.inertia[8] = p->C;
  int good = root_body(b, &d, AP_JOINT_PLANE_CONTACT);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0, c.no_spin = p->no_spin;
  good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), "roll");
  good = good && gravity(b, p->grav);
  if (p->lift > 0) {
    ap_effect_def e = ap_effect_def_default();
    e.name = "lift", e.kind = AP_EFFECT_APPLIED, e.body = 0, e.force[2] = p->lift;
    good = good && ok(b, ap_builder_add_effect(b, &e, NULL), "lift");
  }
  return finish(b, good);
}

int bs_disk_state(const ap_model *m, ap_data *d, double psi, double th, double phi,
                  double thd, double wa, double wn, double *q, double *v) {
  double e1[3] = {cos(psi), sin(psi), 0}, left[3] = {-sin(psi), cos(psi), 0}, a[3], bu[3];
  for (int i = 0; i < 3; i++) {
    a[i] = cos(th) * left[i] - sin(th) * (i == 2);
    bu[i] = sin(th) * left[i] + cos(th) * (i == 2);
  }
  double R0[9], R[9], c = cos(phi), s = sin(phi);
  for (int i = 0; i < 3; i++) R0[i] = e1[i], R0[3 + i] = -bu[i], R0[6 + i] = a[i];
  for (int i = 0; i < 3; i++) {   /* R = R0 Rz(phi) */
    R[i] = c * R0[i] + s * R0[3 + i];
    R[3 + i] = -s * R0[i] + c * R0[3 + i];
    R[6 + i] = R0[6 + i];
  }
  q[0] = 0.1, q[1] = -0.2;
  ap_quat_from_matrix(R, q + 2);
  for (int i = 0; i < 3; i++) v[2 + i] = -thd * e1[i] + wa * bu[i] + wn * a[i];
  const int given[5] = {0, 0, 1, 1, 1};
  return complete(m, d, q, given, v);
}

void bs_disk_steady_rates(const bs_disk *p, double th, double Om, double *wa, double *wn) {
  double mr2 = p->m * p->r * p->r;
  *wa = Om * cos(th);
  *wn = (p->m * p->grav * p->r * sin(th) / (Om * cos(th)) - p->A * Om * sin(th)) /
        (p->C + mr2);
}

double bs_disk_lean(const double *q) {
  double R[9];
  ap_quat_to_matrix(q + 2, R);
  return atan2(-R[8], hypot(R[6], R[7]));
}

void bs_disk_read(const double *q, const double *v, double *th, double *thd, double *wa,
                  double *wn) {
  double R[9], a[3], bu[3], w[3] = {v[2], v[3], v[4]};
  ap_quat_to_matrix(q + 2, R);
  for (int i = 0; i < 3; i++) a[i] = R[6 + i];
  *th = atan2(-a[2], hypot(a[0], a[1]));
  for (int i = 0; i < 3; i++) bu[i] = (i == 2) - a[2] * a[i];
  double nb = sqrt(bu[0] * bu[0] + bu[1] * bu[1] + bu[2] * bu[2]);
  *wa = *wn = 0.0;
  for (int i = 0; i < 3; i++) *wa += w[i] * bu[i] / nb, *wn += w[i] * a[i];
  double azd = w[0] * a[1] - w[1] * a[0];   /* (w x a)_z */
  *thd = -azd / cos(*th);
}

/* ---- a free ball on the ground ------------------------------------------------------------ */

/* The body bd (uniform, of mass) on a free joint with the contact c, gravity g and, when extra
 * is not NULL, that effect after the gravity. */
static ap_model *free_body(ap_body_def *bd, double mass, const ap_constraint_def *c,
                           const double *g, const ap_effect_def *extra) {
  ap_builder *b = builder(bd->name);
  if (!b) return NULL;
  int good = ok(b, ap_body_def_uniform(bd, mass), "body inertia") &&
             ok(b, ap_builder_add_body(b, bd, NULL), bd->name);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_FREE, j.child = 0;
  good = good && ok(b, ap_builder_add_joint(b, &j, NULL), "free joint");
  ap_constraint_def cc = *c;
  cc.body = 0;
  good = good && ok(b, ap_builder_add_constraint(b, &cc, NULL), "contact");
  ap_effect_def e = ap_effect_def_default();
  memcpy(e.gravity, g, sizeof e.gravity);
  good = good && ok(b, ap_builder_add_effect(b, &e, NULL), "gravity");
  if (extra) good = good && ok(b, ap_builder_add_effect(b, extra, NULL), "extra effect");
  if (!good) return ap_builder_free(b), NULL;
  return bs_compile(b);
}

ap_model *bs_free_ball(ap_shape_kind shape, double radius, double mass,
                       const ap_constraint_def *c, const double *g) {
  return bs_free_ball_effect(shape, radius, mass, c, g, NULL);
}

ap_model *bs_free_ball_effect(ap_shape_kind shape, double radius, double mass,
                              const ap_constraint_def *c, const double *g,
                              const ap_effect_def *extra) {
  ap_body_def bd = ap_body_def_default();
  bd.name = "ball", bd.shape.kind = shape, bd.shape.radius = radius;
  return free_body(&bd, mass, c, g, extra);
}

ap_model *bs_leaning_rod(const char *name, double mu, bs_rod *geo) {
  double a = 0.01, c = 0.5, th = 45 * 3.14159265358979323846 / 180, g[3] = {0, 0, -9.81};
  /* body z along (-sin th, 0, cos th) (pitch -th: R = Ry(-th)); u = -R^T e_z = (-sin th, 0,
   * -cos th) in body axes; support point c_b = D^2 u / sqrt(u^T D^2 u); r = R c_b */
  double h = sqrt(a * a * sin(th) * sin(th) + c * c * cos(th) * cos(th));
  double cbx = -a * a * sin(th) / h, cbz = -c * c * cos(th) / h;
  *geo = (bs_rod){a, c, th, h, cos(th) * cbx - sin(th) * cbz, sin(th) * cbx + cos(th) * cbz,
                  (a * a + c * c) / 5};
  ap_body_def bd = ap_body_def_default();
  bd.name = "rod", bd.shape.kind = AP_SHAPE_ELLIPSOID;
  bd.shape.semi_axes[0] = bd.shape.semi_axes[1] = a, bd.shape.semi_axes[2] = c;
  ap_constraint_def cd = ap_constraint_def_default();
  cd.name = name, cd.mu = mu;
  return free_body(&bd, 1.0, &cd, g, NULL);
}

int bs_ball_refused(ap_joint_kind joint, double radius, double mass, const ap_constraint_def *c,
                    char *msg, size_t len) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  int rc = ap_builder_create("refused", &b);
  ap_body_def bd = ap_body_def_default();
  bd.name = "ball", bd.shape.kind = AP_SHAPE_SPHERE, bd.shape.radius = radius;
  if (rc == AP_OK) rc = ap_body_def_uniform(&bd, mass);
  if (rc == AP_OK) rc = ap_builder_add_body(b, &bd, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = joint, j.child = 0;
  if (rc == AP_OK) rc = ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def cc = *c;
  cc.body = 0;
  if (rc == AP_OK) rc = ap_builder_add_constraint(b, &cc, NULL);
  if (rc == AP_OK) rc = ap_builder_compile(b, &m);
  snprintf(msg, len, "%s", b ? ap_builder_message(b) : "");
  if (m) fail("bs_ball_refused", "the model compiled"), rc = AP_OK;
  ap_model_free(m);
  ap_builder_free(b);
  return rc;
}

/* ---- heavy symmetric top ----------------------------------------------------------------- */

bs_top bs_top_default(void) {
  bs_top p = {0.5, 0.1, 2e-3, 3e-3, 9.81};
  return p;
}

ap_model *bs_top_model(const bs_top *p) {
  ap_builder *b = builder("heavy top");
  if (!b) return NULL;
  ap_body_def d = ap_body_def_default();
  d.name = "top", d.mass = p->m, d.com[2] = p->l;
  d.inertia[0] = d.inertia[4] = p->A0, d.inertia[8] = p->C;
  int good = root_body(b, &d, AP_JOINT_BALL) && gravity(b, p->grav);
  return finish(b, good);
}

void bs_top_initial(double q[4], double w[3]) {
  double ex[3] = {1, 0, 0}, R[9];
  ap_quat_from_axis_angle(ex, 0.5, q);
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++) w[i] = 50.0 * R[6 + i] + (i == 2 ? 1.0 : 0.0) + (i == 0 ? 0.3 : 0);
}

/* ---- rattleback ------------------------------------------------------------------------- */

ap_model *bs_rattleback_model(double skew) {
  ap_builder *b = builder("rattleback");
  if (!b) return NULL;
  ap_body_def d = ap_body_def_default();
  d.name = "rattleback", d.shape.kind = AP_SHAPE_ELLIPSOID;
  d.shape.semi_axes[0] = 0.2, d.shape.semi_axes[1] = 0.03, d.shape.semi_axes[2] = 0.02;
  int good = ok(b, ap_body_def_uniform(&d, 1.0), "rattleback inertia");
  /* principal axes turned by skew about z against the shape's: a product term I_xy */
  double c = cos(skew), s = sin(skew), I1 = d.inertia[0], I2 = d.inertia[4];
  d.inertia[0] = c * c * I1 + s * s * I2, d.inertia[4] = s * s * I1 + c * c * I2;
  d.inertia[1] = d.inertia[3] = c * s * (I1 - I2);
  d.com[2] = -0.01;   /* centre of mass below the centre: stable on its bottom */
  good = good && root_body(b, &d, AP_JOINT_PLANE_CONTACT);
  ap_constraint_def con = ap_constraint_def_default();
  con.name = "roll", con.body = 0;
  good = good && ok(b, ap_builder_add_constraint(b, &con, NULL), "roll");
  good = good && gravity(b, 9.81);
  return finish(b, good);
}

int bs_rattleback_state(const ap_model *m, ap_data *d, double rock, double spin, double q[6],
                        double v[5]) {
  const double q0[6] = {0, 0, 1, 0, 0, 0}, v0[5] = {0, 0, 0, rock, spin};
  const int given[5] = {0, 0, 1, 1, 1};
  memcpy(q, q0, sizeof q0), memcpy(v, v0, sizeof v0);
  return complete(m, d, q, given, v);
}

/* ---- twins of the reference systems ------------------------------------------------------- */

static int table_rate(double t, double f[3], void *user) {
  const rs_turntable *p = user;
  f[0] = rs_turntable_omega(p, t);
  f[1] = p->dOmega;
  return 0;
}

ap_model *bs_turntable_model(rs_turntable *p) {
  ap_builder *b = builder("ball on turntable");
  if (!b) return NULL;
  ap_body_def d = ap_body_def_default();
  d.name = "ball", d.shape.kind = AP_SHAPE_SPHERE, d.shape.radius = p->R;
  int good = ok(b, ap_body_def_uniform(&d, p->m), "ball inertia");   /* kI = 2/5 */
  good = good && root_body(b, &d, AP_JOINT_PLANE_CONTACT);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  c.ground.kind = AP_GROUND_TURNTABLE, c.ground.omega_fn = table_rate, c.ground.user = p;
  good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), "roll");
  good = good && gravity(b, 9.81);   /* no generalized force on a sphere */
  return finish(b, good);
}

long bs_turntable_run(const ap_model *m, const rs_turntable *p, const double *q0,
                      const double *v0, const double *qh, const double *vh, const char *method,
                      double rtol, int free_, int *flags, double *err) {
  ap_sim_def def = ap_sim_def_default();
  def.method = method, def.rtol = def.atol = rtol;
  ap_sim *s = NULL;
  int fl[16] = {0}, rc = ap_sim_create(m, &def, 0.0, q0, v0, &s, NULL, 0);
  if (rc == AP_OK && free_ && ap_model_n(m) <= 16) rc = ap_sim_free_coordinates(s, fl);
  if (rc == AP_OK && free_) rc = ap_sim_set_uncontrolled(s, fl);
  if (flags) memcpy(flags, fl, sizeof(int) * (size_t)ap_model_n(m));
  *err = 0.0;
  for (int j = 1; rc == AP_OK && j <= 10; j++) {
    double t = 1.6 * j, qe[5];
    rc = ap_sim_advance(s, t);
    rs_turntable_exact(p, qh, vh, t, qe, NULL);
    for (int c = 0; rc == AP_OK && c < 2; c++) *err = fmax(*err, fabs(ap_sim_q(s)[c] - qe[c]));
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  ap_sim_free(s);
  return rc == AP_OK ? st.steps : -1;
}

ap_model *bs_skate_model(const rs_knife *p) { return bs_skate_model_blades(p, 1); }

ap_model *bs_skate_model_blades(const rs_knife *p, int blades) {
  ap_builder *b = builder(blades > 1 ? "two blades" : "skate");
  if (!b) return NULL;
  double I[3] = {0.5 * p->J + 0.1, 0.5 * p->J + 0.05, p->J}, ey[3] = {0, 1, 0};
  int good = bs_add_body(b, "skate", p->m, NULL, I) == 0;
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANAR, j.child = 0;
  ap_quat_from_axis_angle(ey, p->alpha, j.parent_frame.quat);   /* x down the slope */
  good = good && ok(b, ap_builder_add_joint(b, &j, NULL), "skate joint");
  static const char *names[2] = {"blade", "blade2"};
  for (int i = 0; i < blades && i < 2; i++) {   /* the second: the same blade again */
    ap_constraint_def c = ap_constraint_def_default();
    c.name = names[i], c.kind = AP_CON_KNIFE_EDGE, c.body = 0;
    c.direction[1] = -1.0;   /* refsys row: [sin phi, -cos phi, 0] */
    good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), names[i]);
  }
  good = good && gravity(b, p->grav);
  return finish(b, good);
}

ap_model *bs_sleigh_model(const rs_sleigh *p) {
  ap_builder *b = builder("sleigh");
  if (!b) return NULL;
  double com[3] = {p->a, 0, 0}, I[3] = {0.6 * p->I, 0.6 * p->I, p->I};
  int good = bs_add_body(b, "sleigh", p->m, com, I) == 0;
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANAR, j.child = 0;
  good = good && ok(b, ap_builder_add_joint(b, &j, NULL), "sleigh joint");
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "blade", c.kind = AP_CON_KNIFE_EDGE, c.body = 0;   /* direction (0, 1, 0) */
  good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), "blade");
  return finish(b, good);
}

/* ---- Hoffmann's pendulum ------------------------------------------------------------------ */

rs_hoffmann bs_hoffmann_params(void) {
  rs_hoffmann p = {1.0, 0.8, 0.5, 0.4, 0, 0, 9.81, 2.0};
  p.I1 = p.m1 * p.a1 * p.a1 / 3, p.I2 = p.m2 * p.a2 * p.a2 / 3;
  return p;
}

/* A thin rod with its centre of mass at (0, 0, comz) and inertia I about the hinge axis x (the
 * axial inertia is a small positive number that never enters the planar motion). */
static int rod(ap_builder *b, const char *name, double mass, double comz, double I) {
  double com[3] = {0, 0, comz}, Id[3] = {I, I, 1e-3 * I};
  return bs_add_body(b, name, mass, com, Id);
}

static int hoffmann_effects(ap_builder *b, const rs_hoffmann *p, int lower) {
  if (!gravity(b, p->grav)) return 0;
  if (p->F == 0.0) return 1;
  ap_effect_def e = ap_effect_def_default();
  e.name = "F", e.kind = AP_EFFECT_APPLIED, e.body = lower, e.force[1] = p->F;
  return ok(b, ap_builder_add_effect(b, &e, NULL), "F");
}

/* The upper rod's revolute about x at the origin. */
static ap_joint_def upper_joint(int up) {
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_REVOLUTE, j.child = up, j.axis[0] = 1.0, j.axis[2] = 0.0;
  return j;
}

/* Both rods (ids *up, *lo) and the upper one's revolute. */
static int upper_rod(ap_builder *b, const rs_hoffmann *p, int *up, int *lo) {
  *up = rod(b, "upper", p->m1, -p->a1, p->I1), *lo = rod(b, "lower", p->m2, 0.0, p->I2);
  ap_joint_def j = upper_joint(*up);
  return *up >= 0 && *lo >= 0 && ok(b, ap_builder_add_joint(b, &j, NULL), "upper joint");
}

ap_model *bs_hoffmann_tree(const rs_hoffmann *p, int slide, double y_line) {
  ap_builder *b = builder(slide ? "Hoffmann sliding" : "Hoffmann tree");
  if (!b) return NULL;
  int up, lo, good = upper_rod(b, p, &up, &lo);
  ap_joint_def j = upper_joint(up);
  j.name = "hinge", j.parent = up, j.child = lo;
  j.parent_frame.pos[2] = -2 * p->a1, j.child_frame.pos[2] = p->a2;
  good = good && ok(b, ap_builder_add_joint(b, &j, NULL), "hinge");
  if (slide) {
    ap_constraint_def c = ap_constraint_def_default();
    c.name = "slider", c.kind = AP_CON_POINT_ON_PLANE, c.body = lo, c.body2 = AP_GROUND;
    c.point[2] = -p->a2, c.point2[1] = y_line;   /* normal (0, 1, 0): the default */
    good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), "slider");
  }
  good = good && hoffmann_effects(b, p, lo);
  return finish(b, good);
}

ap_model *bs_hoffmann_primitive(const rs_hoffmann *p) { return bs_hoffmann_primitive_n(p, 1); }

ap_model *bs_hoffmann_primitive_n(const rs_hoffmann *p, int hinges) {
  ap_builder *b = builder("Hoffmann primitive");
  if (!b) return NULL;
  int up, lo, good = upper_rod(b, p, &up, &lo);
  ap_joint_def j = upper_joint(up);
  const double Ryzx[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0};   /* planar x, y, normal -> y, z, x */
  j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANAR, j.child = lo;
  ap_quat_from_matrix(Ryzx, j.parent_frame.quat);
  ap_quat_from_matrix(Ryzx, j.child_frame.quat);
  good = good && ok(b, ap_builder_add_joint(b, &j, NULL), "lower joint");
  static const char *names[2] = {"hinge", "hinge2"};
  for (int i = 0; i < hinges && i < 2; i++) {   /* the second: the same hinge again */
    ap_constraint_def c = ap_constraint_def_default();
    c.name = names[i], c.kind = AP_CON_COINCIDENT, c.body = lo, c.body2 = up, c.axes = 6u;
    c.point[2] = p->a2, c.point2[2] = -2 * p->a1;
    good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), names[i]);
  }
  good = good && hoffmann_effects(b, p, lo);
  return finish(b, good);
}

void bs_hoffmann_primitive_state(const rs_hoffmann *p, double th, double psi, double thd,
                                 double psd, double q[4], double v[4]) {
  double ph = th + psi, phd = thd + psd;
  /* revolute about x: body z axis at angle th from the world z; the upper rod's lower end at
   * 2 a1 (sin th, -cos th) in (y, z) (the body point (0, 0, -2 a1)) */
  double yh = 2 * p->a1 * sin(th), zh = -2 * p->a1 * cos(th);
  double yhd = 2 * p->a1 * cos(th) * thd, zhd = 2 * p->a1 * sin(th) * thd;
  /* the lower rod's point (0, 0, a2) is at the hinge: origin = hinge - a2 (-sin ph, cos ph) */
  q[0] = th, q[1] = yh + p->a2 * sin(ph), q[2] = zh - p->a2 * cos(ph), q[3] = ph;
  v[0] = thd, v[1] = yhd + p->a2 * cos(ph) * phd, v[2] = zhd + p->a2 * sin(ph) * phd;
  v[3] = phd;
}

int bs_hoffmann_sliding_state(const ap_model *m, double q[2], double v[2], double *change) {
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) {
    fail("ap_data_create", "cannot create a data struct");
    return AP_ERR_NOMEM;
  }
  double moved = 0.0;
  const int given[2] = {1, 0};
  q[0] = 0.5, q[1] = -0.5, v[0] = 1.0, v[1] = 0.0;
  d->t = 0.0;
  int rc = ap_body_project_q(m, d, q, &moved);   /* assemble from a rough guess */
  if (rc != AP_OK) fail("ap_body_project_q", d->msg);
  ap_data_free(d);
  if (change) *change = moved;
  return rc == AP_OK ? complete(m, NULL, q, given, v) : rc;
}

/* ---- Chaplygin's ball ----------------------------------------------------------------------- */

ap_model *bs_chaplygin_ball_model(double mass, double a, const double I[3]) {
  ap_builder *b = builder("Chaplygin ball");
  if (!b) return NULL;
  ap_body_def d = ap_body_def_default();
  d.name = "ball", d.mass = mass, d.shape.kind = AP_SHAPE_SPHERE, d.shape.radius = a;
  for (int i = 0; i < 3; i++) d.inertia[4 * i] = I[i];   /* centre of mass at the centre */
  int good = root_body(b, &d, AP_JOINT_PLANE_CONTACT);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  good = good && ok(b, ap_builder_add_constraint(b, &c, NULL), "roll");
  good = good && gravity(b, 9.81);
  return finish(b, good);
}

int bs_chaplygin_ball_state(const ap_model *m, ap_data *d, const double p[4], const double w[3],
                            double q[6], double v[5]) {
  const int given[5] = {0, 0, 1, 1, 1};
  double nn = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
  q[0] = 0.2, q[1] = -0.1;
  for (int i = 0; i < 4; i++) q[2 + i] = p[i] / nn;
  v[0] = v[1] = 0.0, v[2] = w[0], v[3] = w[1], v[4] = w[2];
  return complete(m, d, q, given, v);
}

void bs_chaplygin_ball_momentum(double mass, double a, const double I[3], const double q[6],
                                const double v[5], double K[3]) {
  double R[9], wb[3], Iw[3];
  ap_quat_to_matrix(q + 2, R);   /* body -> world, column-major */
  for (int i = 0; i < 3; i++)    /* body components of w: R^T w */
    wb[i] = R[3 * i] * v[2] + R[3 * i + 1] * v[3] + R[3 * i + 2] * v[4];
  for (int i = 0; i < 3; i++) Iw[i] = I[i] * wb[i];
  for (int i = 0; i < 3; i++) K[i] = R[i] * Iw[0] + R[i + 3] * Iw[1] + R[i + 6] * Iw[2];
  K[0] += -mass * a * v[1], K[1] += mass * a * v[0];   /* m (G - P) x v_G = m a e_z x v_G */
}

void bs_dae_cases(bs_case c[BS_DAE_CASES]) {
  memset(c, 0, sizeof(bs_case) * BS_DAE_CASES);
  bs_disk dp = bs_disk_default();
  c[0].name = "rolling disk", c[0].m = bs_disk_model(&dp);
  if (c[0].m) bs_disk_state(c[0].m, NULL, 0.3, 0.25, 0.7, 0.4, 1.2, 7.0, c[0].q0, c[0].v0);
  c[1].name = "rattleback", c[1].m = bs_rattleback_model(0.1);
  if (c[1].m) bs_rattleback_state(c[1].m, NULL, 0.02, 5.0, c[1].q0, c[1].v0);
  static rs_turntable tp = {1.2, 0.3, 0.4, 1.1, 0.25};   /* the model keeps a pointer to it */
  double t5[5];
  c[2].name = "ball on turntable", c[2].m = bs_turntable_model(&tp);
  rs_turntable_initial(&tp, 0.5, -0.2, 1.0, 2.0, 3.0, t5, c[2].v0);
  c[2].q0[0] = t5[0], c[2].q0[1] = t5[1], c[2].q0[2] = 1.0;
  const double I[3] = {2e-3, 3e-3, 4.5e-3}, p[4] = {0.9, 0.2, -0.3, 0.1}, w[3] = {1, -2, 3};
  c[3].name = "Chaplygin ball", c[3].m = bs_chaplygin_ball_model(1.0, 0.1, I);
  if (c[3].m) bs_chaplygin_ball_state(c[3].m, NULL, p, w, c[3].q0, c[3].v0);
  rs_hoffmann hp = bs_hoffmann_params();
  c[4].name = "Hoffmann sliding", c[4].m = bs_hoffmann_tree(&hp, 1, 0.3);
  if (c[4].m) bs_hoffmann_sliding_state(c[4].m, c[4].q0, c[4].v0, NULL);
  c[5].name = "Hoffmann hinge", c[5].m = bs_hoffmann_primitive(&hp);
  bs_hoffmann_primitive_state(&hp, 0.3, -0.5, 0.5, 0.6, c[5].q0, c[5].v0);
}

void bs_disk_turn_free(const bs_disk *p, double th, double Om, double psi, double *q,
                       double *v) {
  double wa, wn, e1[3] = {cos(psi), sin(psi), 0}, left[3] = {-sin(psi), cos(psi), 0};
  double a[3], bu[3], R[9], w[3];
  bs_disk_steady_rates(p, th, Om, &wa, &wn);
  for (int i = 0; i < 3; i++) {
    a[i] = cos(th) * left[i] - sin(th) * (i == 2);
    bu[i] = sin(th) * left[i] + cos(th) * (i == 2);
  }
  for (int i = 0; i < 3; i++) R[i] = e1[i], R[3 + i] = -bu[i], R[6 + i] = a[i];  /* columns */
  q[0] = 0.1, q[1] = -0.2, q[2] = p->r * cos(th);
  ap_quat_from_matrix(R, q + 3);
  for (int i = 0; i < 3; i++) w[i] = wa * bu[i] + wn * a[i], v[3 + i] = w[i];
  v[0] = p->r * (w[1] * bu[2] - w[2] * bu[1]);   /* vc = r w x bu: the contact point at rest */
  v[1] = p->r * (w[2] * bu[0] - w[0] * bu[2]);
  v[2] = p->r * (w[0] * bu[1] - w[1] * bu[0]);
}
