/* Finite-difference checks of the body layer along the motion (fdcheck.h). */
#include <stdio.h>
#include <string.h>

#include "fdcheck.h"
#include "testrand.h"

/* ---- random numbers (tests/testrand.h, fixed seed) ---------------------------------------- */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
double urand(void) { return ap_test_urand(&rng_state); }
double srand1(void) { return ap_test_srand(&rng_state); }
void rand_vec(double *x, int n, double s) {
  for (int i = 0; i < n; i++) x[i] = s * srand1();
}
void rand_quat(double *q) {
  double n = 0.0;
  for (int i = 0; i < 4; i++) q[i] = srand1(), n += q[i] * q[i];
  n = sqrt(n);
  for (int i = 0; i < 4; i++) q[i] /= n;
}
void rand_frame(ap_frame *f) {
  rand_vec(f->pos, 3, 0.3);
  rand_quat(f->quat);
}
/* A random physical inertia: R diag(l) R^T, l in [1, 1.5] * scale (triangle inequality). */
void rand_inertia(double *I, double scale) {
  double q[4], R[9], l[3];
  rand_quat(q);
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++) l[i] = scale * (1.0 + 0.5 * urand());
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double s = 0.0;
      for (int c = 0; c < 3; c++) s += R[i + 3 * c] * l[c] * R[j + 3 * c];
      I[i + 3 * j] = s;
    }
}

/* ---- time functions used by drives, turntables, prescribed speeds ---------------------------- */

int f_sine(double t, double f[3], void *user) {
  double a = user ? *(double *)user : 1.0, w = 1.3;
  f[0] = 0.5 * a * sin(w * t) + 0.2 * t;
  f[1] = 0.5 * a * w * cos(w * t) + 0.2;
  f[2] = -0.5 * a * w * w * sin(w * t);
  return 0;
}
int f_omega(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.7 + 0.3 * sin(0.9 * t);
  f[1] = 0.27 * cos(0.9 * t);
  return 0;
}
int f_vel(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.4 * cos(1.1 * t);
  f[1] = -0.44 * sin(1.1 * t);
  return 0;
}

/* ---- measurements along the path ------------------------------------------------------------ */

static const double probe[3] = {0.13, -0.21, 0.17};

/* The material contact point of each body with a contact: c_b (body axes) at s = 0, held
 * fixed on the body at the other points of the path (freeze). */
static double contact_cb[MAXB][3];
static int freeze;

static void measure_contact(const ap_model *m, ap_data *d, int b, const ap_body_state *st,
                            const double *v, meas *out) {
  double Jv[3 * MAXK], rv[3], *cb = contact_cb[b];
  if (!st->has_contact) return;
  if (!freeze) {   /* c_b = R^T (x_c - o) */
    for (int i = 0; i < 3; i++) {
      cb[i] = 0.0;
      for (int j = 0; j < 3; j++) cb[i] += st->R[j + 3 * i] * (st->contact[j] - st->pos[j]);
    }
  }
  ap_body_point_jacobian(m, d, b, cb, NULL, Jv, NULL, rv, NULL, NULL);
  for (int i = 0; i < 3; i++) {
    out->xm[b][i] = st->pos[i], out->vm[b][i] = rv[i];
    for (int j = 0; j < 3; j++) out->xm[b][i] += st->R[i + 3 * j] * cb[j];
    for (int c = 0; c < m->k; c++) out->vm[b][i] += Jv[i + 3 * c] * v[c];
  }
  out->zc[b] = st->contact[2];
}

int measure(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
            meas *out) {
  int nb = ap_model_body_count(m), k = m->k;
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)m->n);
  memcpy(d->v, v, sizeof(double) * (size_t)k);
  d->basis = AP_BASIS_NONE, d->speeds_from_e = 0;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(m, d);
  if (rc != AP_OK) return rc;
  for (int b = 0; b < nb; b++) {
    ap_body_state st;
    double Jw[3 * MAXK], Jv[3 * MAXK], rw[3], rv[3];
    ap_body_get_state(m, d, b, &st);
    ap_body_point_jacobian(m, d, b, probe, Jw, Jv, rw, rv, out->aw[b], out->av[b]);
    memcpy(out->R[b], st.R, sizeof st.R);
    for (int i = 0; i < 3; i++) {
      out->x[b][i] = st.pos[i];
      for (int j = 0; j < 3; j++) out->x[b][i] += st.R[i + 3 * j] * probe[j];
      out->w[b][i] = rw[i], out->vp[b][i] = rv[i];
      for (int c = 0; c < k; c++)
        out->w[b][i] += Jw[i + 3 * c] * v[c], out->vp[b][i] += Jv[i + 3 * c] * v[c];
    }
    measure_contact(m, d, b, &st, v, out);
  }
  for (int s = 0; s < m->b; s++) {
    out->c[s] = d->a0[s], out->gamma[s] = d->gamma[s];
    for (int c = 0; c < k; c++) out->c[s] += d->A[s + (size_t)c * m->b] * v[c];
  }
  out->QV = 0.0;
  for (int c = 0; c < k; c++) out->QV += d->Q[c] * v[c];
  double T = 0.0;
  return ap_body_energy(m, d, &T, &out->V);
}

/* All fields of a meas as one flat array, so differences apply to everything at once. */
#define MEAS_N (sizeof(meas) / sizeof(double))

double err_rel(const double *an, const double *fd, int n) {
  double e = 0.0, s = 1.0;
  for (int i = 0; i < n; i++) s = fmax(s, fabs(an[i]));
  for (int i = 0; i < n; i++) e = fmax(e, fabs(an[i] - fd[i]));
  return e / s;
}

/* Richardson-extrapolated derivative of every field along the path. */
int fd_along(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
             const double *qd, double h, meas *der) {
  static meas f[4];
  const double sgn[4] = {1, -1, 0.5, -0.5};
  double qs[MAXK];
  freeze = 1;   /* the contact points of s = 0 stay fixed on their bodies */
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < m->n; j++) qs[j] = q[j] + sgn[i] * h * qd[j];
    int rc = measure(m, d, t + sgn[i] * h, qs, v, &f[i]);
    if (rc != AP_OK) return freeze = 0, rc;
  }
  freeze = 0;
  double *D = (double *)der, *f0 = (double *)&f[0], *f1 = (double *)&f[1],
         *f2 = (double *)&f[2], *f3 = (double *)&f[3];
  for (size_t i = 0; i < MEAS_N; i++) {
    double Dh = (f0[i] - f1[i]) / (2 * h), Dh2 = (f2[i] - f3[i]) / h;
    D[i] = (4 * Dh2 - Dh) / 3;
  }
  return AP_OK;
}

int fd_check(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
             double h, fd_result *res, meas *aout, meas *dout) {
  static meas a, der;
  double qd[MAXK];
  int nb = ap_model_body_count(m), rc = measure(m, d, t, q, v, &a);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < m->n; i++) {
    qd[i] = 0.0;
    for (int c = 0; c < m->k; c++) qd[i] += d->N[i + (size_t)c * m->n] * v[c];
  }
  rc = fd_along(m, d, t, q, v, qd, h, &der);
  if (rc != AP_OK) return rc;
  memset(res, 0, sizeof *res);
  for (int b = 0; b < nb; b++) {
    double w[3], *Rd = der.R[b], *R = a.R[b], W[9];
    for (int i = 0; i < 3; i++)   /* W = R' R^T */
      for (int j = 0; j < 3; j++)
        W[i + 3 * j] = Rd[i] * R[j] + Rd[i + 3] * R[j + 3] + Rd[i + 6] * R[j + 6];
    w[0] = 0.5 * (W[2 + 3 * 1] - W[1 + 3 * 2]);
    w[1] = 0.5 * (W[0 + 3 * 2] - W[2 + 3 * 0]);
    w[2] = 0.5 * (W[1 + 3 * 0] - W[0 + 3 * 1]);
    res->vel = fmax(res->vel, err_rel(a.vp[b], der.x[b], 3));
    res->omega = fmax(res->omega, err_rel(a.w[b], w, 3));
    res->alpha = fmax(res->alpha, err_rel(a.aw[b], der.w[b], 3));
    res->acc = fmax(res->acc, err_rel(a.av[b], der.vp[b], 3));
    ap_body_state st;
    ap_body_get_state(m, d, b, &st);   /* st: the last point of the path (contact or not) */
    if (!st.has_contact) continue;
    res->contact = fmax(res->contact, err_rel(a.vm[b], der.xm[b], 3));
    res->contact = fmax(res->contact, err_rel(&a.vm[b][2], &der.zc[b], 1));
  }
  double mg[MAXR], pw = -a.QV;
  for (int s = 0; s < m->b; s++) mg[s] = -a.gamma[s];
  res->gamma = m->b ? err_rel(mg, der.c, m->b) : 0.0;
  res->power = err_rel(&pw, &der.V, 1);
  if (aout) *aout = a;
  if (dout) *dout = der;
  return AP_OK;
}

/* Random state: coordinates (quaternions unit), speeds, time. */
void rand_state(const ap_model *m, double *q, double *v, double *t) {
  rand_vec(q, m->n, 1.0);
  for (int i = 0; i < m->n; i++) {
    const char *nm = ap_model_coord_name(m, i);
    const char *dot = strrchr(nm, '.');
    if (dot && strcmp(dot, ".qw") == 0) rand_quat(q + i), i += 3;
  }
  rand_vec(v, m->k, 1.0);
  *t = 2.0 * urand();
}

/* Run fd_check at several random states and assert every error; returns the worst. */
/* 1 when every body with a contact is at least min_flat (|sin| of its axis tilt) from lying
 * flat. */
static int away_from_flat(const ap_model *m, ap_data *d, double min_flat) {
  for (int b = 0; b < ap_model_body_count(m); b++) {
    ap_body_state st;
    ap_body_get_state(m, d, b, &st);
    if (st.has_contact && fabs(st.R[8]) > sqrt(1 - min_flat * min_flat)) return 0;
  }
  return 1;
}

fd_result fd_many(const char *label, const ap_model *m, int samples, int check_power,
                  double min_flat) {
  ap_data *d = NULL;
  fd_result worst = {0, 0, 0, 0, 0, 0, 0};
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  for (int s = 0; s < samples; s++) {
    double q[MAXK], v[MAXK], t;
    fd_result r;
    int rc;
    do {   /* keep disks and tori away from lying flat in the generic samples */
      rand_state(m, q, v, &t);
      rc = measure(m, d, t, q, v, &(meas){0});
      if (rc == AP_OK && min_flat > 0 && !away_from_flat(m, d, min_flat)) rc = 1;
    } while (rc != AP_OK);
    rc = fd_check(m, d, t, q, v, 1e-3, &r, NULL, NULL);
    AP_CHECK(rc == AP_OK);
    worst.vel = fmax(worst.vel, r.vel), worst.omega = fmax(worst.omega, r.omega);
    worst.alpha = fmax(worst.alpha, r.alpha), worst.acc = fmax(worst.acc, r.acc);
    worst.gamma = fmax(worst.gamma, r.gamma), worst.power = fmax(worst.power, r.power);
    worst.contact = fmax(worst.contact, r.contact);
  }
  printf("  %-22s vel %.1e  omega %.1e  alpha %.1e  acc %.1e  gamma %.1e  power %.1e  "
         "contact %.1e\n", label, worst.vel, worst.omega, worst.alpha, worst.acc, worst.gamma,
         check_power ? worst.power : 0.0, worst.contact);
  AP_CHECK_LE(worst.vel, FD_TOL);
  AP_CHECK_LE(worst.omega, FD_TOL);
  AP_CHECK_LE(worst.alpha, FD_TOL);
  AP_CHECK_LE(worst.acc, FD_TOL);
  AP_CHECK_LE(worst.gamma, FD_TOL);
  AP_CHECK_LE(worst.contact, FD_TOL);
  if (check_power) AP_CHECK_LE(worst.power, FD_TOL);
  ap_data_free(d);
  return worst;
}


ap_model *fd_free_shape(const char *name, int kind, const ap_constraint_def *c) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_builder_create(name, &b), AP_OK);
  ap_body_def bd = ap_body_def_default();
  bd.name = "wheel", bd.mass = 1.3;
  bd.shape.kind = (ap_shape_kind)kind, bd.shape.radius = 0.4, bd.shape.tube = 0.07;
  bd.shape.semi_axes[0] = 0.5, bd.shape.semi_axes[1] = 0.3, bd.shape.semi_axes[2] = 0.2;
  rand_vec(bd.com, 3, 0.1), rand_inertia(bd.inertia, 0.05);
  AP_CHECK_EQ_INT(ap_builder_add_body(b, &bd, NULL), AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_FREE, j.child = 0;
  AP_CHECK_EQ_INT(ap_builder_add_joint(b, &j, NULL), AP_OK);
  ap_constraint_def cc = *c;
  cc.body = 0;
  AP_CHECK_EQ_INT(ap_builder_add_constraint(b, &cc, NULL), AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK_EQ_INT(ap_builder_add_effect(b, &e, NULL), AP_OK);
  AP_CHECK_EQ_INT(ap_builder_compile(b, &m), AP_OK);
  ap_builder_free(b);
  return m;
}
