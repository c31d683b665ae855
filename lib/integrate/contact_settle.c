/* Consistent contact modes at a switch state (docs/scenes.md "Friction, slip and lift-off",
 * "Consistent modes"): after a switch hook, an impact or at creation, each contact with modes
 * is checked against what its mode gives at (t, q, v), one contact at a time, until none
 * contradicts its mode:
 *   rolling   F_n < 0 (unilateral)            -> airborne
 *             |F_t| > mu F_n                   -> sliding along -F_t
 *   sliding   F_n < 0 (unilateral)            -> airborne
 *   airborne  touching (gap <= gap_tol, closing speed >= -v_tol) and its gap would fall:
 *             gap'' = A_n v'_air - gamma_n < 0 -> rolling when the rolling forces are
 *             admissible there (F_n >= 0, in the cone), else sliding (along the slip, or
 *             -F_t when the slip is round-off)
 * (A_n, gamma_n the contact's normal row in the rolling mode, v'_air the accelerations with
 * the contact airborne: at gap = gap' = 0 the gap's second derivative.) A contradiction
 * counts only beyond SETTLE_BAND rtol of its scale (the largest multiplier or acceleration):
 * at the switch that made the mode the deciding value is 0 (a lift-off's F_n, a slip onset's
 * cone margin), and runs of one model differ by about rtol there, so a value inside the band
 * keeps the mode the event chose, identically in every mode and method. A cycle (a set of
 * modes met twice) means that no mode of the contacts is consistent (Painleve's paradox, a
 * wheel the ground would have to pull in every mode): the run stops and says so. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "integrate/contact_int.h"

#define SETTLE_BAND 1e3   /* relative to rtol: decisions inside it keep the mode */
#define SETTLE_SEEN 64    /* mode sets remembered (cycle detection) */

typedef struct settle_ctx {
  ap_sim *s;
  const ap_bmodel *M;
  double t, *q, *vd;
  double *v;
  double fn_roll, ft_roll[2], gdd;   /* an airborne contact's rolling forces and gap'' */
  int turns;                         /* slip directions turned (bounded) */
} settle_ctx;

static double *scr(const ap_sim *s) { return ap_bm_scratch(s->d); }
static int mode_of(const settle_ctx *x, const ap_mcon *c) {
  return ap_cfr_mode(x->M, scr(x->s), c);
}

static double vmax_of(const double *v, int k) {
  double m = 0.0;
  for (int j = 0; j < k; j++) m = fmax(m, fabs(v[j]));
  return m;
}

/* The band of a force contradiction: SETTLE_BAND rtol times the largest force around. */
static double force_band(const ap_sim *s, double fn, const double *ft) {
  double m = fmax(fabs(fn), hypot(ft[0], ft[1]));
  for (int i = 0; i < s->b; i++) m = fmax(m, fabs(s->d->lambda[i]));
  return SETTLE_BAND * s->def.rtol * m;
}

/* The code of the current set of modes (base 3; contacts beyond 40 share digits: the
 * iteration bound then ends a cycle). */
static uint64_t modes_code(const settle_ctx *x) {
  uint64_t code = 0;
  for (int ci = 0, i = 0; ci < x->M->nc; ci++)
    if (x->M->cons[ci].fric >= 0 && i++ < 40)
      code = 3 * code + (uint64_t)mode_of(x, &x->M->cons[ci]);
  return code;
}

/* Airborne contact c touching the ground: gap'' with the contact airborne (the data hold the
 * airborne evaluation), and the rolling forces, from an evaluation with c rolling. 1 when its
 * gap clearly falls, 0 when not (or not touching), negative on failure. */
static int gap_falls(settle_ctx *x, const ap_mcon *c) {
  ap_sim *s = x->s;
  ap_data *d = s->d;
  int k = s->k, b = s->b, r = c->row + c->hrow;
  if (!c->nhol || ap_bm_wheel_by_load(x->M, c)) return 0;
  double gap = ap_contact_gap(x->M, scr(s), c), vm = vmax_of(x->v, k);
  if (gap > s->def.atol + s->def.rtol * s->m->lscale) return 0;
  memcpy(x->vd, d->vdot, sizeof(double) * (size_t)k);
  ap_cfr_set_mode(x->M, scr(s), c, AP_CM_ROLLING);
  int rc = ap_drv_cm_forces(s, x->t, x->q, x->v);
  double vn = d->a0[r], an = -d->gamma[r];
  for (int j = 0; j < k; j++) vn += d->A[r + (size_t)j * b] * x->v[j];
  for (int j = 0; j < k; j++) an += d->A[r + (size_t)j * b] * x->vd[j];
  if (rc == AP_OK) x->fn_roll = ap_drv_cm_normal(s, d->lambda, c, x->ft_roll);
  if (rc == AP_OK) ap_drv_cm_determinate(s, c, x->ft_roll);
  ap_cfr_set_mode(x->M, scr(s), c, AP_CM_AIRBORNE);
  int rc2 = ap_drv_cm_forces(s, x->t, x->q, x->v);   /* the airborne data back */
  if (rc != AP_OK) return 0;   /* rolling has no solution here: the mode stays */
  if (rc2 != AP_OK) return rc2 < 0 ? rc2 : AP_ERR_SINGULAR;
  x->gdd = an;
  if (vn > s->def.atol + s->def.rtol * vm) return 0;   /* opening: it flies */
  return an < -SETTLE_BAND * s->def.rtol * (vmax_of(x->vd, k) + fabs(d->gamma[r]));
}

/* Airborne c back on the ground (its gap would fall): rolling when the rolling forces are
 * admissible, else sliding along the slip (or against the sticking force). */
static void touch(settle_ctx *x, const ap_mcon *c) {
  ap_sim *s = x->s;
  double sl[2], *S = scr(s), mu = c->def.mu, fn = x->fn_roll, *ft = x->ft_roll;
  double band = force_band(s, fn, ft);
  ap_cfr_slip(x->M, S, c, x->v, sl);
  double ns = hypot(sl[0], sl[1]);
  int slips = mu >= 0 && ns > s->def.atol + s->def.rtol * vmax_of(x->v, s->k);
  if (!slips && (!(mu >= 0) || hypot(ft[0], ft[1]) <= mu * fn + band) && fn >= -band) {
    ap_cfr_set_mode(x->M, S, c, AP_CM_ROLLING);
    return;
  }
  if (slips) {
    double *dir = ap_cfr_slip_dir(x->M, S, c);
    dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
    ap_cfr_set_mode(x->M, S, c, AP_CM_SLIDING);
  } else {
    ap_drv_cm_slide_against(s, c, ft);
  }
}

/* Sliding contact c whose slip is round-off (a slip onset, or a contact whose slip another
 * contact's stick has taken away): rolling when the rolling forces lie clearly inside the
 * cone (1); else its slip acceleration s' = A_t v'_slide - gamma_t must point along the slip
 * direction the friction opposes: a direction it contradicts is turned to s' / |s'| (1, at
 * most 8 turns: 2); 0 when the mode stands. The data hold the sliding evaluation on return. */
static int stick_or_turn(settle_ctx *x, const ap_mcon *c) {
  ap_sim *s = x->s;
  ap_data *d = s->d;
  int k = s->k, b = s->b;
  double sl[2], vm = vmax_of(x->v, k), *dir = ap_cfr_slip_dir(x->M, scr(s), c);
  ap_cfr_slip(x->M, scr(s), c, x->v, sl);
  if (hypot(sl[0], sl[1]) > s->def.atol + s->def.rtol * vm) return 0;
  memcpy(x->vd, d->vdot, sizeof(double) * (size_t)k);
  ap_cfr_set_mode(x->M, scr(s), c, AP_CM_ROLLING);
  double ft[2], fn = 0.0, sa[2] = {0.0, 0.0}, band = 0.0;
  int rc = ap_drv_cm_forces(s, x->t, x->q, x->v);
  if (rc == AP_OK) {
    fn = ap_drv_cm_normal(s, d->lambda, c, ft), band = force_band(s, fn, ft);
    ap_drv_cm_determinate(s, c, ft);
    for (int r = 0; r < 2; r++) {
      sa[r] = -d->gamma[c->row + r];
      for (int j = 0; j < k; j++) sa[r] += d->A[c->row + r + (size_t)j * b] * x->vd[j];
    }
    if (fn > band && hypot(ft[0], ft[1]) < c->def.mu * fn - band) return 1;   /* sticks */
  }
  ap_cfr_set_mode(x->M, scr(s), c, AP_CM_SLIDING);
  int rc2 = ap_drv_cm_forces(s, x->t, x->q, x->v);
  if (rc2 != AP_OK) return rc2 < 0 ? rc2 : AP_ERR_SINGULAR;
  double na = hypot(sa[0], sa[1]);
  if (rc != AP_OK || x->turns >= 8 ||
      !(sa[0] * dir[0] + sa[1] * dir[1] < -SETTLE_BAND * s->def.rtol * (vmax_of(x->vd, k) + na)))
    return 0;
  dir[0] = sa[0] / na, dir[1] = sa[1] / na;
  x->turns++;
  return 2;
}

/* v onto the current modes' velocity rows, nearest in g (as the driver's restart will put
 * it): a contact that has just stuck still carries the slip of the state before, and the
 * forces there would be those of an inconsistent state (two wheels of one axle: their
 * sideways rows' gamma disagree). */
static int project_speeds(settle_ctx *x) {
  ap_sim *s = x->s;
  ap_data *d = s->d;
  ap_basis basis = d->basis;
  int sfe = d->speeds_from_e;
  d->t = x->t, d->speeds_from_e = 0, d->basis = AP_BASIS_ORTHONORMAL;
  memcpy(d->q, x->q, sizeof(double) * (size_t)s->n);
  int rc = ap_partition(s->m, d);
  if (rc == AP_OK) rc = ap_fwd_position(s->m, d);
  if (rc == AP_OK) rc = ap_core_project_here(s->m, d, x->v, NULL);
  d->basis = basis, d->speeds_from_e = sfe;
  s->ev_stamp = -1;
  return rc;
}

/* The first contact that contradicts its mode, changed; 1 when one was (2: a slip direction
 * turned), 0 when none. */
static int settle_one(settle_ctx *x, char *lifted) {
  ap_sim *s = x->s;
  const ap_bmodel *M = x->M;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0) continue;
    int mode = mode_of(x, c), uni = ap_cfr_unilateral(c);
    double ft[2], fn = ap_drv_cm_normal(s, s->d->lambda, c, ft), band = force_band(s, fn, ft);
    if (mode != AP_CM_AIRBORNE && uni && fn < -band) {
      if (ap_bm_wheel_by_load(M, c)) return ap_drv_cm_tips(s, c, x->t, fn);
      if (lifted) lifted[ci] = 1;
      int rc = ap_drv_cm_lift(s, c, x->t, x->q);
      return rc == AP_OK ? 1 : ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact '%s' "
                                           "lifting off at t = %.17g: %s", c->name, x->t,
                                           s->d->msg);
    }
    if (mode == AP_CM_ROLLING && c->def.mu >= 0) ap_drv_cm_determinate(s, c, ft);
    if (mode == AP_CM_ROLLING && c->def.mu >= 0 && hypot(ft[0], ft[1]) > c->def.mu * fn + band) {
      ap_drv_cm_slide_against(s, c, ft);
      return 1;
    }
    if (mode == AP_CM_SLIDING && c->def.mu >= 0) {
      int st = stick_or_turn(x, c);
      if (st < 0) return ap_drv_fail(s, st, "contact '%s' at t = %.17g: %s", c->name, x->t,
                                     s->d->msg);
      if (st) return st;
    }
    if (mode != AP_CM_AIRBORNE) continue;
    int falls = gap_falls(x, c);
    if (falls < 0) return ap_drv_fail(s, falls, "contact '%s' at t = %.17g: %s", c->name, x->t,
                                      s->d->msg);
    if (falls) {
      if (lifted) lifted[ci] = 0;
      touch(x, c);
      return 1;
    }
  }
  return 0;
}

/* No consistent mode: the run stops, naming the contacts' values. */
static int no_mode(settle_ctx *x) {
  return ap_drv_fail(x->s, AP_ERR_SINGULAR, "contact modes at t = %.17g: no consistent mode "
                     "(a contact's modes contradict each other: rolling needs F_n < 0 or more "
                     "friction than mu, sliding F_n < 0, and flying a falling gap, gap'' = %.6g): "
                     "the contact problem has no solution here (Painleve's paradox or a "
                     "wheel the ground would have to pull); lower mu or change the state",
                     x->t, x->gdd);
}

/* Contacts whose mode differs from was (by constraint): recorded as their switches. */
static int note_changes(settle_ctx *x, char *was) {
  int rc = AP_OK;
  for (int ci = 0; rc == AP_OK && ci < x->M->nc; ci++) {
    const ap_mcon *c = &x->M->cons[ci];
    if (c->fric < 0 || mode_of(x, c) == was[ci]) continue;
    rc = ap_drv_cm_note(x->s, c, was[ci], mode_of(x, c), x->t, x->q, x->v);
    was[ci] = (char)mode_of(x, c);
  }
  return rc;
}

int ap_drv_cm_settle(ap_sim *s, double t, double *q, double *v, int *changed, char *lifted,
                     int note) {
  settle_ctx x = {s, ap_bm(s->m), t, q, NULL, v, 0.0, {0.0, 0.0}, 0.0, 0};
  uint64_t seen[SETTLE_SEEN];
  int nseen = 0, rc = AP_OK;
  x.vd = malloc(sizeof(double) * (size_t)(s->k + 1));
  char *was = malloc((size_t)x.M->nc + 1);
  if (!x.vd || !was) {
    free(x.vd), free(was);
    return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  }
  for (int ci = 0; ci < x.M->nc; ci++)
    was[ci] = x.M->cons[ci].fric >= 0 ? (char)mode_of(&x, &x.M->cons[ci]) : 0;
  *changed = 0;
  for (int iter = 0; rc == AP_OK; iter++) {
    uint64_t code = modes_code(&x);
    for (int i = 0; i < nseen; i++)
      if (seen[i] == code) rc = no_mode(&x);
    if (rc != AP_OK || iter > 3 * x.M->nfric + 3 + x.turns) {
      rc = rc != AP_OK ? rc : no_mode(&x);
      break;
    }
    if (nseen < SETTLE_SEEN) seen[nseen++] = code;
    rc = project_speeds(&x);
    if (rc == AP_OK) rc = ap_drv_cm_forces(s, t, q, v);
    if (rc != AP_OK) {
      rc = ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact modes at t = %.17g: %s", t,
                       s->d->msg);
      break;
    }
    int one = settle_one(&x, lifted);
    if (one <= 0) {
      rc = one;
      break;
    }
    if (one == 2) nseen = 0;   /* the same modes with a turned direction: not a cycle */
    *changed = 1;
    if (note && (rc = note_changes(&x, was)) != AP_OK) break;
  }
  free(x.vd);
  free(was);
  return rc;
}
