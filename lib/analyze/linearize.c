/* The linearizer (include/appell/analyze.h): creation, the operating point, the linearization
 * and its queries.
 *
 * A = dF/dx at the operating point x0 column by column (jacobian.c): by complex step, exact to
 * round-off, where the model allows it; else with Ridders' method (ridders.c), first step
 * h0 max(1, |x0_j|), the round-off floor of its estimates from the noise of F measured at x0
 * (ap_an_noise: near a steady motion F is small while the terms it is made of are not, so a
 * noise relative to |F| would be far too small). Aerr holds the estimates. B = dF/dtau for a
 * generalized force tau on model speed s is exact: the Appell solve is affine in Q, so dv'/dtau = B_c G^-1 B_c^T e_s with
 * the core's basis B_c and the factor of G = B_c^T g B_c left by the evaluation at x0, and at x0
 * the heading frames are the identity (du'/dtau = dv'/dtau); coordinate rows are zero.
 * Cyclic states: start from every coordinate state and drop a state while its column has a
 * non-zero entry in a row outside the set (greatest fixed point: the largest set C with
 * A[not C, C] = 0). Zero means |A_ij| <= 4 Aerr_ij + zero_tol max|A|. Steady: F(x0) vanishes
 * outside C (within 1e-9 of the rates' scale, or 10 tol). Time-dependent models (drives,
 * moving ground) are linearized at the given t after checking that F(x0) is the same at t + 1
 * and t + 10 (a turntable turning at a constant rate is autonomous). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "appell/body.h"
#include "core/defcheck.h"
#include "linalg/linalg.h"
#include "model/setpoint.h"

ap_lin_def ap_lin_def_default(void) {
  ap_lin_def d;
  memset(&d, 0, sizeof d);
  d.about = AP_LIN_STEADY;
  d.tol = 1e-12;
  d.max_iter = 40;
  d.zero_tol = 1e-9;
  d.h0 = 0.01;
  d.method = AP_LIN_AUTO;
  d.internal_check = AP_DEF_CHECK;
  return d;
}

void ap_an_msg(ap_lin *L, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(L->msg, sizeof L->msg, fmt, ap);
  va_end(ap);
}

const char *ap_lin_message(const ap_lin *L) { return L ? L->msg : "no linearizer"; }

const char *ap_an_var_name(const ap_lin *L, int i) {
  if (i < 0) return "?";
  if (i < L->ch.nc) return L->ch.names[i];
  return i - L->ch.nc < L->k ? ap_model_speed_name(L->m, i - L->ch.nc) : "?";
}

int ap_an_find_var(const ap_lin *L, const char *name) {
  for (int i = 0; name && i < L->ch.nc + L->k; i++)
    if (strcmp(ap_an_var_name(L, i), name) == 0) return i;
  return -1;
}

/* ---- creation ---------------------------------------------------------------------------- */

/* A NULL-terminated copy of a NULL-terminated list, in one block; *ok = 0 on failure. */
static char **copy_list(const char *const *list, int *ok) {
  if (!list) return NULL;
  size_t n = 0, bytes = 0;
  for (; list[n]; n++) bytes += strlen(list[n]) + 1;
  char **out = malloc((n + 1) * sizeof *out + bytes);
  if (!out) return *ok = 0, NULL;
  char *p = (char *)(out + n + 1);
  for (size_t i = 0; i < n; i++) {
    size_t len = strlen(list[i]) + 1;
    memcpy(p, list[i], len);
    out[i] = p, p += len;
  }
  out[n] = NULL;
  return out;
}

/* Scratch for Ridders' columns and the noise estimate. */
static size_t ridders_size(int nv) {
  size_t a = ap_an_ridders_scratch(nv), b = (size_t)(AP_AN_NOISE_PTS + 1) * nv + nv;
  return a > b ? a : b;
}

static int alloc_all(ap_lin *L) {
  int n = L->n, k = L->k, b = L->b, np = L->nphi, nc = L->ch.nc;
  size_t mk = (size_t)(k > nc ? k : nc), mb = (size_t)(b > np ? b : np), nv = (size_t)nc + k;
  size_t big = mk * mk + (size_t)np * n + (size_t)b * k + 1;
  L->nwork = ap_la_work_size((int)mb, (int)mk);
  struct { double **p; size_t len; } part[] = {
      {&L->q_ref, n}, {&L->v_ref, k}, {&L->q_guess, n}, {&L->v_guess, k}, {&L->delta, nc},
      {&L->dq, (size_t)n * nc}, {&L->Jh, (size_t)np * nc}, {&L->phi, np + 1}, {&L->Au, big},
      {&L->Bu, big}, {&L->dd, big}, {&L->b0u, mk + 1}, {&L->F, mb * mk + 1},
      {&L->tau, mk + mb + 1}, {&L->u, k}, {&L->udot, k}, {&L->f1, 2 * nv}, {&L->f2, nv},
      {&L->x0, nv}, {&L->A, nv * nv}, {&L->Aerr, nv * nv}, {&L->Bm, nv * k}, {&L->F0, nv},
      {&L->noise, nv}, {&L->ridders, ridders_size((int)nv)}, {&L->work, L->nwork}};
  size_t np_ = sizeof part / sizeof *part, nd = 0;
  for (size_t i = 0; i < np_; i++) nd += part[i].len + 1;
  double *p = calloc(nd, sizeof *p);
  L->iwork = calloc(ap_la_iwork_size((int)mb, (int)mk) + 4 * nv + 8, sizeof *L->iwork);
  if (!p || !L->iwork) return free(p), AP_ERR_NOMEM;
  for (size_t i = 0; i < np_; i++) *part[i].p = p, p += part[i].len + 1;
  int *ip = L->iwork + ap_la_iwork_size((int)mb, (int)mk);
  L->cperm = ip, ip += nv + 1, L->uperm = ip, ip += nv + 1, L->xvar = ip, ip += nv + 1;
  L->cyclic = ip;
  L->ws = (an_ws){L->d,  L->delta, L->dq, L->Jh,  L->phi,  L->Bu, L->Au,
                  L->Bu, L->b0u,   L->F,  L->tau, L->u,    L->dd, L->work, L->f2};
  L->inputs = calloc((size_t)k + 1, sizeof *L->inputs);
  return L->inputs ? ap_an_eigen_alloc(L) : AP_ERR_NOMEM;
}

static int bind_inputs(ap_lin *L) {
  for (const char *const *s = L->def.inputs; s && *s; s++) {
    int i = ap_model_find_speed(L->m, *s), e = i < 0 ? ap_act_find_setpoint(L->m, *s) : -1;
    if (i < 0 && e >= 0) i = -1 - e;   /* a motor's set-point (model/setpoint.h) */
    else if (i < 0) {
      const char **names = calloc((size_t)L->k + 1, sizeof *names);
      for (int j = 0; names && j < L->k; j++) names[j] = ap_model_speed_name(L->m, j);
      const char *sug = names ? ap_suggest(*s, names, L->k) : NULL;
      ap_an_msg(L, "inputs: '%s' is not a speed of model '%s' nor MOTOR.setpoint of a motor "
                "with a constant set-point%s%s%s", *s, ap_model_name(L->m),
                sug ? " (did you mean '" : "", sug ? sug : "", sug ? "'?)" : "");
      free(names);
      L->bad_list = "inputs", L->bad_index = (int)(s - L->def.inputs);   /* located by scene */
      return AP_ERR_ARG;
    }
    if (L->nu >= L->k) break;
    L->inputs[L->nu++] = i;
  }
  return AP_OK;
}

/* Every name of list (def.free or def.independent) is a state variable: a chart coordinate or
 * a model speed. Else AP_ERR_ARG, the message with the closest name ("did you mean") or the
 * variables, and the entry in L->bad_list, L->bad_index (the scene layer locates it). */
static int check_var_names(ap_lin *L, const char *const *list, const char *what) {
  for (int i = 0; list && list[i]; i++) {
    if (ap_an_find_var(L, list[i]) >= 0) continue;
    int nv = L->ch.nc + L->k;
    const char **names = calloc((size_t)nv + 1, sizeof *names);
    for (int j = 0; names && j < nv; j++) names[j] = ap_an_var_name(L, j);
    const char *sug = names ? ap_suggest(list[i], names, nv) : NULL;
    char hint[300] = "";
    size_t used = 0;
    if (sug) snprintf(hint, sizeof hint, "did you mean '%s'?", sug);
    for (int j = 0; !sug && names && j < nv && used + 8 < sizeof hint; j++)
      used += (size_t)snprintf(hint + used, sizeof hint - used, "%s%s", j ? ", " : "the state "
                               "variables are ", names[j]);
    free(names);
    ap_an_msg(L, "%s: '%s' is not a state variable of model '%s' (%s)", what, list[i],
              ap_model_name(L->m), hint);
    L->bad_list = what, L->bad_index = i;
    return AP_ERR_ARG;
  }
  return AP_OK;
}

/* The guess must be finite: a NaN or an infinity would only show up later as a failed Newton. */
static int check_guess(ap_lin *L, const double *q, const double *v) {
  for (int i = 0; i < L->n; i++)
    if (!isfinite(q[i])) {
      ap_an_msg(L, "linearizer for model '%s': coordinate %d (%s) of the guess is %g",
                ap_model_name(L->m), i, ap_model_coord_name(L->m, i), q[i]);
      return AP_ERR_ARG;
    }
  for (int i = 0; v && i < L->k; i++)
    if (!isfinite(v[i])) {
      ap_an_msg(L, "linearizer for model '%s': speed %d (%s) of the guess is %g",
                ap_model_name(L->m), i, ap_model_speed_name(L->m, i), v[i]);
      return AP_ERR_ARG;
    }
  for (int i = 0; L->def.speed_dir && i < L->k; i++)
    if (!isfinite(L->def.speed_dir[i])) {
      ap_an_msg(L, "linearizer for model '%s': speed_dir[%d] (%s) is %g", ap_model_name(L->m), i,
                ap_model_speed_name(L->m, i), L->def.speed_dir[i]);
      return AP_ERR_ARG;
    }
  return AP_OK;
}

static void normalize_quats(ap_lin *L) {
  for (int i = 0; i < L->ch.nquat; i++) {
    double *p = L->q_ref + L->ch.quat[i].q;
    double nn = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
    if (nn > 0 && isfinite(nn))
      for (int j = 0; j < 4; j++) p[j] /= nn;
  }
}

static int setup(ap_lin *L, const ap_lin_def *def, double t, const double *q, const double *v) {
  int ok = 1;
  if (def && def->internal_check != AP_DEF_CHECK) {   /* before its lists are read */
    ap_an_msg(L, "ap_lin_def " AP_DEF_NOT_DEFAULT("ap_lin_def"));
    return AP_ERR_ARG;
  }
  L->def = def ? *def : ap_lin_def_default();
  L->def.free = (const char *const *)(L->names = copy_list(L->def.free, &ok));
  char **indep = copy_list(L->def.independent, &ok), **inputs = copy_list(L->def.inputs, &ok);
  L->def.independent = (const char *const *)indep, L->def.inputs = (const char *const *)inputs;
  if (!ok) return AP_ERR_NOMEM;
  L->n = ap_model_n(L->m), L->k = ap_model_k(L->m), L->b = ap_model_b(L->m);
  L->nphi = L->m->nphi, L->t = t;
  if (L->m->sys.kinematic && L->n != L->k && !ap_model_is_body_model(L->m)) {
    ap_an_msg(L, "model '%s' has a kinematic matrix N with n = %d != k = %d: the linearization "
              "needs coordinates whose rates are the speeds", ap_model_name(L->m), L->n, L->k);
    return AP_ERR_UNSUPPORTED;
  }
  if (L->m->ops) {   /* the tree path's data has no A or B */
    ap_an_msg(L, "model '%s' is on the tree path: the linearization needs the dense path "
              "(path: dense)", ap_model_name(L->m));
    return AP_ERR_UNSUPPORTED;
  }
  int rc = check_guess(L, q, v);
  if (rc == AP_OK) rc = ap_data_create(L->m, &L->d);
  if (rc == AP_OK) rc = ap_an_chart_build(L->m, &L->ch, L->msg, sizeof L->msg);
  if (rc == AP_OK) rc = alloc_all(L);
  if (rc == AP_OK) rc = check_var_names(L, L->def.free, "free");
  if (rc == AP_OK) rc = check_var_names(L, L->def.independent, "independent");
  if (rc != AP_OK) return rc;
  memcpy(L->q_ref, q, sizeof *q * (size_t)L->n);
  if (v) memcpy(L->v_ref, v, sizeof *v * (size_t)L->k);
  normalize_quats(L);
  ap_an_chart_centre(&L->ch, L->q_ref, 0);
  memcpy(L->q_guess, L->q_ref, sizeof *q * (size_t)L->n);
  memcpy(L->v_guess, L->v_ref, sizeof *q * (size_t)L->k);
  if (L->def.speed_dir) {
    L->speed_dir = malloc(sizeof *L->speed_dir * (size_t)L->k);
    if (!L->speed_dir) return AP_ERR_NOMEM;
    memcpy(L->speed_dir, L->def.speed_dir, sizeof *L->speed_dir * (size_t)L->k);
    L->def.speed_dir = L->speed_dir;
  }
  return bind_inputs(L);
}

/* Contacts with modes (friction, lift-off) that slide or fly at (t, q, v); 0 without them. */
static int contacts_off(const ap_model *m, double t, const double *q, const double *v) {
  ap_data *d = NULL;
  if (!ap_model_is_body_model(m) || ap_data_create(m, &d) != AP_OK) return 0;
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)ap_model_n(m));
  int off = ap_body_contact_modes(m, d, v, 1e-6);
  ap_data_free(d);
  return off;
}

int ap_lin_create(const ap_model *m, const ap_lin_def *def, double t, const double *q,
                  const double *v, ap_lin **out) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  if (!m || !q || !isfinite(t)) return AP_ERR_ARG;
  ap_lin *L = calloc(1, sizeof *L);
  if (!L) return AP_ERR_NOMEM;
  L->m = m;
  int rc = setup(L, def, t, q, v);
  int off = rc == AP_OK && v ? contacts_off(m, t, q, v) : 0;
  if (off > 0) {   /* contact modes: the linearization is about the rolling motion */
    rc = AP_ERR_UNSUPPORTED;
    ap_an_msg(L, "linearizer for model '%s': at this state %d contact%s with friction or "
              "lift-off slide%s or fly: a linearization is about motions where every contact "
              "rolls", ap_model_name(m), off, off == 1 ? "" : "s", off == 1 ? "s" : "");
  }
  if (rc != AP_OK && rc != AP_ERR_NOMEM && L->msg[0] == '\0')
    ap_an_msg(L, "linearizer for model '%s': %s", ap_model_name(m), ap_strerror(rc));
  *out = L;   /* even on failure, so that ap_lin_message can tell why; free it */
  return rc;
}

void ap_lin_free(ap_lin *L) {
  if (!L) return;
  ap_data_free(L->d);
  ap_an_ws_cs_free(L);
  ap_an_chart_free(&L->ch);
  ap_an_eigen_free(L);
  free(L->q_ref);
  free(L->iwork);
  free(L->inputs);
  free(L->names);
  free((void *)L->def.independent);
  free((void *)L->def.inputs);
  free(L->speed_dir);
  free(L);
}

/* ---- the operating point ----------------------------------------------------------------- */

int ap_lin_operating_point(ap_lin *L, double s) {
  if (!L || !L->d) return AP_ERR_ARG;
  L->msg[0] = '\0';
  if (isinf(s)) {
    ap_an_msg(L, "operating point: the speed parameter is %g (a finite value, or NaN to keep "
              "the speeds)", s);
    return AP_ERR_ARG;
  }
  L->linearized = 0;
  int rc = AP_OK;
  if (!L->parted) {
    rc = ap_an_partition(L);
    if (rc != AP_OK) return rc;
    for (int i = 0; i < L->nci; i++) L->x0[i] = 0.0;
    for (int j = 0; j < L->l; j++) L->x0[L->nci + j] = L->v_ref[L->uperm[L->ru + j]];
  }
  if (L->speed_dir && isfinite(s))   /* the speeds not freed: v_guess + s v_dir */
    for (int j = 0; j < L->l; j++) {
      int sp = L->uperm[L->ru + j], freed = 0;
      for (const char *const *f = L->def.free; f && *f && !freed; f++)
        freed = strcmp(*f, ap_model_speed_name(L->m, sp)) == 0;
      if (!freed) L->x0[L->nci + j] = L->v_guess[sp] + s * L->speed_dir[sp];
    }
  return ap_an_newton(L);
}

const double *ap_lin_q(const ap_lin *L) { return L ? L->q_ref : NULL; }
const double *ap_lin_v(const ap_lin *L) { return L ? L->v_ref : NULL; }

/* ---- the linearization ------------------------------------------------------------------- */

static double max_abs(const double *x, size_t n) {
  double m = 0.0;
  for (size_t i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* The model must not depend on t explicitly: F at x0 and at a point 0.01 away (the Jacobian
 * could depend on t where F does not) is the same at t + 1 and t + 10 as at t. */
static int check_autonomous(ap_lin *L) {
  if (!L->m->sys.rheonomic) return AP_OK;
  double t0 = L->t, worst = 0.0, scale = fmax(1.0, max_abs(L->F0, (size_t)L->nx));
  double *x = L->f1, *f = L->f1 + L->nx, *f0 = L->noise;   /* f1 holds 2 nx, noise nx */
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < 3; i++) {
      for (int j = 0; j < L->nx; j++)
        x[j] = L->x0[j] + (k ? 0.01 * (((j * 7 + 3) % 5) - 2.0) / 2.0 : 0.0);
      L->t = t0 + (i == 0 ? 0.0 : i == 1 ? 1.0 : 10.0);
      int rc = ap_an_rates(L, x, i == 0 ? f0 : f);
      L->t = t0;
      if (rc != AP_OK) return rc;
      for (int r = 0; i > 0 && r < L->nx; r++) worst = fmax(worst, fabs(f[r] - f0[r]));
    }
  if (worst <= 1e-10 * scale) return AP_OK;
  ap_an_msg(L, "model '%s' depends on time explicitly (drives or a ground whose motion changes): "
            "the rates at the operating point change by %.3g between t = %g and t + 10, so it "
            "has no steady motion to linearize about", ap_model_name(L->m), worst, t0);
  return AP_ERR_UNSUPPORTED;
}

/* B: exact response of the independent speed rates to unit generalized forces; for a motor's
 * set-point, to the force g on its speed that a unit change of the set-point makes (g = kd or
 * kp, 0 while saturated: d tau / d s of the motor's law). */
static int input_matrix(ap_lin *L) {
  ap_data *d = L->d;
  int k = L->k, l = d->l, nx = L->nx;
  memset(L->Bm, 0, sizeof *L->Bm * (size_t)nx * (L->nu ? L->nu : 1));
  for (int c = 0; c < L->nu; c++) {
    double *e = L->u, *t = L->udot, *dv = L->f1;   /* e: k, t: l, dv: k */
    memset(e, 0, sizeof *e * (size_t)k);
    if (L->inputs[c] >= 0) e[L->inputs[c]] = 1.0;
    else {
      int col = 0, rc = ap_act_setpoint_gain(L->m, d, -1 - L->inputs[c], &col, &e[0]);
      if (rc != AP_OK) return ap_an_msg(L, "inputs: '%s': %s", L->def.inputs[c], d->msg), rc;
      double g = e[0];
      e[0] = 0.0, e[col] = g;
    }
    ap_la_gemv_t(k, l, d->B, e, t);
    ap_la_chol_solve(l, d->G, t);
    ap_la_gemv(k, l, d->B, t, dv);
    for (int j = 0; j < L->l; j++) L->Bm[L->nci + j + (size_t)c * nx] = dv[L->uperm[L->ru + j]];
  }
  return AP_OK;
}

static int is_zero(const ap_lin *L, int r, int c, double amax) {
  size_t i = r + (size_t)c * L->nx;
  return fabs(L->A[i]) <= 4.0 * L->Aerr[i] + L->def.zero_tol * amax;
}

static void find_cyclic(ap_lin *L) {
  int nx = L->nx, changed = 1;
  double amax = max_abs(L->A, (size_t)nx * nx);
  for (int i = 0; i < nx; i++) L->cyclic[i] = i < L->nci;
  while (changed) {
    changed = 0;
    for (int c = 0; c < L->nci; c++) {
      if (!L->cyclic[c]) continue;
      for (int r = 0; r < nx && L->cyclic[c]; r++)
        if (!L->cyclic[r] && !is_zero(L, r, c, amax)) L->cyclic[c] = 0, changed = 1;
    }
  }
}

static int check_steady(ap_lin *L) {
  double scale = fmax(1.0, max_abs(L->F0, (size_t)L->nx));
  for (int j = 0; j < L->l; j++) scale = fmax(scale, L->x0[L->nci + j] * L->x0[L->nci + j]);
  double thr = fmax(1e-9, 10.0 * L->def.tol) * scale;
  for (int i = 0; i < L->nx; i++)
    if (!L->cyclic[i] && fabs(L->F0[i]) > thr) {
      ap_an_msg(L, "not an operating point: '%s' changes at the rate %.6g there (only cyclic "
                "coordinates may move in a steady motion; free the variables to adjust, or "
                "choose the equilibrium)", ap_an_var_name(L, L->xvar[i]), L->F0[i]);
      return AP_ERR_INCONSISTENT;
    }
  return AP_OK;
}

int ap_lin_linearize(ap_lin *L) {
  if (!L || !L->d) return AP_ERR_ARG;
  int rc = L->parted ? AP_OK : ap_lin_operating_point(L, NAN);
  if (rc != AP_OK) return rc;
  L->msg[0] = '\0';
  L->linearized = 0;
  rc = ap_an_rates(L, L->x0, L->F0);
  if (rc == AP_OK) rc = check_autonomous(L);
  if (rc == AP_OK) rc = ap_an_jacobian(L);
  if (rc == AP_OK) rc = ap_an_rates(L, L->x0, L->F0);   /* leaves the data at x0 */
  if (rc != AP_OK) return rc;
  rc = input_matrix(L);
  if (rc != AP_OK) return rc;
  find_cyclic(L);
  rc = check_steady(L);
  L->linearized = rc == AP_OK;
  return rc;
}

/* ---- queries ------------------------------------------------------------------------------- */

int ap_lin_nx(const ap_lin *L) { return L && L->parted ? L->nx : 0; }
int ap_lin_nu(const ap_lin *L) { return L ? L->nu : 0; }

const char *ap_lin_state_name(const ap_lin *L, int i) {
  return L && L->parted && i >= 0 && i < L->nx ? ap_an_var_name(L, L->xvar[i]) : NULL;
}

const char *ap_lin_input_name(const ap_lin *L, int j) {
  if (!L || j < 0 || j >= L->nu) return NULL;
  return L->inputs[j] >= 0 ? ap_model_speed_name(L->m, L->inputs[j]) : L->def.inputs[j];
}

int ap_lin_is_cyclic(const ap_lin *L, int i) {
  return L && L->linearized && i >= 0 && i < L->nx ? L->cyclic[i] : 0;
}

int ap_lin_find_state(const ap_lin *L, const char *name) {
  for (int i = 0; L && name && L->parted && i < L->nx; i++)
    if (strcmp(ap_an_var_name(L, L->xvar[i]), name) == 0) return i;
  return -1;
}

const double *ap_lin_A(const ap_lin *L) { return L && L->linearized ? L->A : NULL; }
const double *ap_lin_A_error(const ap_lin *L) { return L && L->linearized ? L->Aerr : NULL; }
const double *ap_lin_B(const ap_lin *L) { return L && L->linearized ? L->Bm : NULL; }
const double *ap_lin_rates(const ap_lin *L) { return L && L->linearized ? L->F0 : NULL; }
ap_lin_method ap_lin_method_used(const ap_lin *L) {
  return L && L->linearized ? L->used : AP_LIN_AUTO;
}
const char *ap_lin_fallback(const ap_lin *L) { return L ? L->fallback : ""; }
