/* Contact modes of a simulation: rolling, sliding and airborne contacts switched by events
 * (docs/scenes.md "Friction, slip and lift-off"; the rows each mode drops and the Coulomb
 * force: model/con_friction.c).
 *
 * At creation (before the initial state is put on the constraints) each contact with modes
 * starts airborne when it is unilateral and its gap exceeds init_tol, sliding when it has a
 * friction coefficient and its slip speed exceeds init_tol (1 + max |v_i|), else rolling.
 * Each such contact then has up to four events of the events machinery (event.c), all
 * AP_EVENT_SWITCH, falling, at the reactions stage, each +1 while its mode is not the one it
 * watches:
 *   NAME.slip      rolling:   mu F_n - |F_t|         -> sliding, slip along -F_t / |F_t|
 *                                                       (airborne when F_n <= 0, unilateral)
 *   NAME.lift_off  rolling, sliding: F_n             -> airborne (sliding: while the slip is
 *                                                       resolved, see stick_value)
 *   NAME.stick     sliding:   s . s_ref               -> rolling when the sticking force lies
 *                                                       in the cone, else sliding along -F_t
 *   NAME.touchdown airborne:  the gap                 -> rolling, sliding or airborne (the
 *                                                       impact, contact_impact.c)
 * s_ref is the slip direction at the last accepted step (the "contact modes" stage after the
 * events stage keeps it): s . s_ref falls through 0 where the slip speed reaches 0.
 *
 * A switch changes the mode (the rows the model drops) in the data; the driver then restarts
 * the stepper at the event with ap_drv_restart_state, which puts q on the new holonomic rows
 * and v on the new velocity rows nearest in the kinetic-energy metric. At touchdown the hook
 * has made the impact's velocity jump already (sticking, sliding or bouncing: contact_impact.c),
 * which that projection keeps. The number of free
 * speeds changes at a switch: in minimal mode the stepper is created again for the new state
 * size (sim.c); in DAE mode IDA is made again (contact_dae.c), and the events read the forces
 * from IDA's multipliers (a wheel under a planar chassis: its load at IDA's accelerations and
 * multipliers, dae_loads.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "integrate/contact_int.h"
#include "linalg/linalg.h"

enum { EV_SLIP, EV_LIFT, EV_STICK, EV_TOUCH, EV_N };
static const char *const ev_suffix[EV_N] = {"slip", "lift_off", "stick", "touchdown"};

typedef struct cm_event {
  struct ap_drv_contacts *cm;
  int ci, kind;
  int idx;           /* its index among the simulation's events; -1 when not added */
} cm_event;

struct ap_drv_contacts {
  ap_sim *s;
  int nc;            /* contacts with modes */
  int *ci;           /* their constraint index */
  cm_event *ev;      /* EV_N per contact */
  double *lam;       /* (b + nphi) DAE mode: IDA's multipliers at an event's time */
  double *vd;        /* (k, after lam) DAE mode: IDA's accelerations there (dae_loads.c) */
  char *armed;       /* (by constraint) 1 + the mode whose leaving event is armed (below) */
  char *lifted;      /* (by constraint) made airborne at t0 by its negative normal force */
  char *made;        /* (by constraint) DAE mode: the modes IDA was made for */
  double *gap0;      /* (by constraint) a bounce's gap at its impact, NAN otherwise */
  double *share;     /* ((b + 2) k) contact_share.c's scratch */
};

/* A contact that has just left the ground has a gap of third order in the time (at lift-off
 * the centre's path osculates the ground), below the integration error at first: IDA's BDF,
 * restarted at order 1, made it -2.5e-12 m 2e-6 s after a lift-off, and the touchdown event
 * fired there. Its touchdown watches gap + gap_tol (while it closes: touchdown_value) until
 * the gap at an accepted step exceeds gap_tol = atol + rtol lscale (the "contact modes" stage
 * arms it), the gap alone after that.
 * Likewise a slip that starts from 0 (slip onset) has s . s_ref of round-off size at first,
 * and the stick event was recorded at the slip's own time: it watches s . s_ref + slip_tol,
 * slip_tol = atol + rtol max |v_i|, until |s| exceeds slip_tol at an accepted step. */
static double gap_tol(const ap_sim *s) { return s->def.atol + s->def.rtol * s->m->lscale; }
static double slip_tol(const ap_sim *s, const double *v) {
  double vmax = 0.0;
  for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(v[j]));
  return s->def.atol + s->def.rtol * vmax;
}
/* A contact that bounced leaves the ground at a clear speed: its touchdown watches the gap
 * from the impact's own (round-off) gap on, gap - gap0 + 1e-14 lscale (the bounce's next
 * touchdown to round-off, however low the bounce); after a lift-off, gap + gap_tol. */
static double unarmed_gap(const struct ap_drv_contacts *cm, int ci) {
  const ap_sim *s = cm->s;
  double g0 = cm->gap0[ci];
  return isnan(g0) ? gap_tol(s) : 1e-14 * s->m->lscale - g0;
}
static int armed(const struct ap_drv_contacts *cm, int ci, int mode) {
  return cm->armed[ci] == mode + 1;
}
int ap_drv_cm_slip_young(const ap_sim *s, const ap_mcon *c) {   /* contact_dae.c */
  return !armed(s->cm, (int)(c - ap_bm(s->m)->cons), AP_CM_SLIDING);
}
/* The touchdown's value: after a lift-off (unarmed, no bounce) the contact lands only while
 * it closes (gap' < 0); while it opens its gap counts as 0 at most. A restarted CVODE `bdf`
 * steps at order 1, whose position error h^2 a / 2 points along gravity every step: it put
 * the ball on the dome 9.7e-10 m (= gap_tol at rtol 1e-8) below the ground 2.5e-5 s after its
 * lift-off, the contact opening (gap' +2e-8 m/s, gap'' +1.4e-3 m/s^2, the true gap +1e-13 m),
 * and the touchdown fired there, again after each restart (a sticking impact and a lift-off
 * every 2.5e-5 s). The value is never below gap + gap_tol: a run without such a touchdown is
 * the same. */
static double touchdown_value(const struct ap_drv_contacts *cm, const ap_mcon *c, double *S,
                              const double *v) {
  const ap_bmodel *M = ap_bm(cm->s->m);
  int ci = (int)(c - M->cons);
  double rate, g = ap_contact_gap_rate(M, S, c, v, &rate);
  if (armed(cm, ci, AP_CM_AIRBORNE)) return g;
  if (isnan(cm->gap0[ci]) && !(rate < 0.0)) g = fmax(g, 0.0);
  return g + unarmed_gap(cm, ci);
}

static const ap_mcon *con(const ap_sim *s, int ci) { return &ap_bm(s->m)->cons[ci]; }
static double *scratch(const ap_data *d) { return ap_bm_scratch(d); }

static double mu_of(const ap_mcon *c) { return c->def.mu; }
static int unilateral(const ap_mcon *c) { return ap_cfr_unilateral(c); }

void ap_drv_contacts_free(ap_sim *s) {
  if (!s->cm) return;
  free(s->cm->ci);
  free(s->cm->ev);
  free(s->cm->lam);
  free(s->cm->armed);
  free(s->cm->gap0);
  free(s->cm->share);
  free(s->cm);
  s->cm = NULL;
}

int ap_drv_contacts_init(ap_sim *s, double t0, const double *q0, const double *v0) {
  if (!ap_model_is_body_model(s->m) || ap_bm(s->m)->nfric == 0) return AP_OK;
  const ap_bmodel *M = ap_bm(s->m);
  s->cm = calloc(1, sizeof *s->cm);
  if (s->cm) s->cm->ci = calloc((size_t)M->nfric, sizeof(int));
  if (s->cm && s->cm->ci) s->cm->ev = calloc((size_t)M->nfric * EV_N, sizeof(cm_event));
  if (s->cm) s->cm->lam = calloc((size_t)(s->b + s->m->nphi + s->k) + 1, sizeof(double));
  if (s->cm && s->cm->lam) s->cm->vd = s->cm->lam + s->b + s->m->nphi;
  if (s->cm) s->cm->armed = calloc(3 * (size_t)M->nc, 1);
  if (s->cm) s->cm->gap0 = malloc(sizeof(double) * (size_t)(M->nc + 1));
  if (s->cm) s->cm->share = malloc(sizeof(double) * ((size_t)(s->b + 2) * (size_t)s->k + 1));
  for (int ci = 0; s->cm && s->cm->gap0 && ci < M->nc; ci++) s->cm->gap0[ci] = NAN;
  if (s->cm && s->cm->armed)
    s->cm->lifted = s->cm->armed + M->nc, s->cm->made = s->cm->lifted + M->nc;
  if (!s->cm || !s->cm->ci || !s->cm->ev || !s->cm->lam || !s->cm->armed || !s->cm->gap0 ||
      !s->cm->share)
    return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  s->cm->s = s;
  ap_data *d = s->d;
  d->t = t0, d->speeds_from_e = 0;
  memcpy(d->q, q0, sizeof(double) * (size_t)s->n);
  int rc = ap_body_contact_modes(s->m, d, v0, s->def.init_tol);
  if (rc < 0) return ap_drv_fail(s, rc, "initial state: %s", d->msg);
  for (int ci = 0; ci < M->nc; ci++)
    if (M->cons[ci].fric >= 0) s->cm->ci[s->cm->nc++] = ci;
  return AP_OK;
}

/* The data at (t, q, v) with the accelerations and the multipliers, whatever the mode's
 * basis (the hooks' view of the state). */
int ap_drv_cm_forces(ap_sim *s, double t, const double *q, const double *v) {
  ap_data *d = s->d;
  ap_basis basis = d->basis;
  int sfe = d->speeds_from_e;
  d->t = t, d->speeds_from_e = 0, d->basis = AP_BASIS_ORTHONORMAL;
  memcpy(d->q, q, sizeof(double) * (size_t)s->n);
  memcpy(d->v, v, sizeof(double) * (size_t)s->k);
  int rc = ap_forward(s->m, d);
  if (rc == AP_OK) rc = ap_fwd_reactions(s->m, d);
  d->basis = basis, d->speeds_from_e = sfe;
  s->ev_stamp = -1;
  return rc;
}

double *ap_drv_cm_share_scratch(ap_sim *s) { return s->cm ? s->cm->share : NULL; }

/* Normal force and tangential force (2) of contact c from the multipliers lam (the data's, or
 * IDA's own in DAE mode); a wheel under a planar chassis: its load (model/loads.c). */
double ap_drv_cm_normal(const ap_sim *s, const double *lam, const ap_mcon *c, double *ft) {
  ft[0] = lam[c->row], ft[1] = lam[c->row + 1];
  return ap_cfr_contact_normal(s->m, s->d, lam, c);
}

/* A wheel under a planar chassis cannot leave the ground: the run stops. */
int ap_drv_cm_tips(ap_sim *s, const ap_mcon *c, double t, double fn) {
  return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "contact '%s': the wheel's load falls to %.6g N at "
                     "t = %.17g: the vehicle would tip or lift that wheel, which a planar "
                     "chassis cannot (its joint keeps the chassis level): put the chassis on a "
                     "free joint (docs/vehicles.md)", c->name, fn, t);
}

/* F_n and F_t of contact c for its events at t: in DAE mode from IDA's own multipliers lam
 * and accelerations (dae_loads.c), else from the data's. */
static double normal_at(struct ap_drv_contacts *cm, double t, const double *lam,
                        const ap_mcon *c, double *ft) {
  return cm->s->dae ? ap_drv_dae_cm_normal(cm->s, t, lam, c, cm->vd, ft)
                    : ap_drv_cm_normal(cm->s, lam, c, ft);
}

/* The stick event's value: s . s_ref (+ slip_tol while the slip has just begun). */
static double stick_value(const struct ap_drv_contacts *cm, int ci, const ap_bmodel *M,
                          double *S, const ap_mcon *c, const double *v) {
  const double *dir = ap_cfr_slip_dir(M, S, c);
  double sl[2];
  ap_cfr_slip(M, S, c, v, sl);
  return sl[0] * dir[0] + sl[1] * dir[1] +
         (armed(cm, ci, AP_CM_SLIDING) ? 0.0 : slip_tol(cm->s, v));
}

/* A sliding contact's lift_off watches F_n only while its slip is resolved: once a slip that
 * had grown beyond slip_tol (its stick armed) has fallen below it again, or a slip that has
 * just begun has passed 0, the slip's direction is below the run's tolerance, and so is the
 * direction of its friction and, where the friction has a moment, F_n. There the stick comes
 * first (within slip_tol / (mu_k F_n) of a time at Coulomb's deceleration), and the settle
 * after it decides from the rolling forces, which do not depend on a direction. (Seed 150 of
 * the tester: in DAE mode with 16 outputs, at a slip of 2.6e-12 m/s on its way to the stick,
 * IDA's F_n swung between -0.33 and 6.6 N within 1e-13 s as s / |s| turned, the lift_off
 * fired before the stick, and the contact flew and landed at once where every other run
 * stuck with F_n = 13.7 N.) The value there is |F_n|: no crossing. */
static int value(double t, const double *q, const double *v, const ap_data *d, void *user,
                 double *out) {
  const cm_event *e = user;
  const ap_bmodel *M = ap_bm(e->cm->s->m);
  const ap_mcon *c = &M->cons[e->ci];
  double *S = scratch(d), ft[2];
  const double *lam = d->lambda;
  ap_sim *s = e->cm->s;
  int mode = ap_cfr_mode(M, S, c);
  (void)q;
  *out = 1.0;
  if (s->dae && (e->kind == EV_SLIP || e->kind == EV_LIFT) && mode != AP_CM_AIRBORNE) {
    if (ap_drv_dae_event_multipliers(s, t, e->cm->lam) != 0) return -1;   /* IDA's own */
    lam = e->cm->lam;
  }
  switch (e->kind) {
    case EV_SLIP:
      if (mode == AP_CM_ROLLING) {
        double fn = normal_at(e->cm, t, lam, c, ft);
        ap_drv_cm_determinate(s, c, ft);
        *out = mu_of(c) * fn - hypot(ft[0], ft[1]);
      }
      break;
    case EV_LIFT:
      if (mode != AP_CM_AIRBORNE) *out = normal_at(e->cm, t, lam, c, ft);
      if (mode == AP_CM_SLIDING && stick_value(e->cm, e->ci, M, S, c, v) <
                                      (armed(e->cm, e->ci, AP_CM_SLIDING) ? slip_tol(s, v) : 0.0))
        *out = fabs(*out);   /* at the stick: the stick comes first (above) */
      break;
    case EV_STICK:
      if (mode == AP_CM_SLIDING) *out = stick_value(e->cm, e->ci, M, S, c, v);
      break;
    default:
      if (mode == AP_CM_AIRBORNE) *out = touchdown_value(e->cm, c, S, v);
      break;
  }
  return 0;
}

/* Sliding along -F_t / |F_t| (the sticking force's direction opposes the slip to come). */
void ap_drv_cm_slide_against(ap_sim *s, const ap_mcon *c, const double *ft) {
  double *dir = ap_cfr_slip_dir(ap_bm(s->m), scratch(s->d), c), nt = hypot(ft[0], ft[1]);
  if (nt > 0) dir[0] = -ft[0] / nt, dir[1] = -ft[1] / nt;
  ap_cfr_set_mode(ap_bm(s->m), scratch(s->d), c, AP_CM_SLIDING);
}

/* Before a contact flies: q onto the rolling mode's manifold, so that the gap the touchdown
 * event watches starts at round-off (IDA holds it only to its tolerance), then airborne. */
int ap_drv_cm_lift(ap_sim *s, const ap_mcon *c, double t, double *q) {
  double *x = malloc(sizeof(double) * (size_t)s->n);
  if (!x) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  memcpy(x, q, sizeof(double) * (size_t)s->n);
  int rc = ap_drv_consistent_coordinates(s, t, x, q);
  free(x);
  ap_cfr_set_mode(ap_bm(s->m), scratch(s->d), c, AP_CM_AIRBORNE);
  return rc;
}

/* The forces at a switch's state, or the run's failure naming the event. */
static int hook_forces(ap_sim *s, const ap_event_record *rec, const double *q, const double *v) {
  int rc = ap_drv_cm_forces(s, rec->t, q, v);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "event '%s' at "
                                           "t = %.17g: %s", rec->name, rec->t, s->d->msg);
}

/* The switch's own mode change; then every contact's mode made consistent (settle). */
static int on_switch(const ap_event_record *rec, double *q, double *v, void *user) {
  const cm_event *e = user;
  ap_sim *s = e->cm->s;
  const ap_bmodel *M = ap_bm(s->m);
  const ap_mcon *c = &M->cons[e->ci];
  double ft[2], fn;
  int changed = 0, bounced = 0;
  switch (e->kind) {
    case EV_SLIP:
      if (hook_forces(s, rec, q, v) != AP_OK) return -1;
      fn = ap_drv_cm_normal(s, s->d->lambda, c, ft);
      ap_drv_cm_determinate(s, c, ft);
      if (unilateral(c) && fn <= 0 && ap_bm_wheel_by_load(M, c))
        return ap_drv_cm_tips(s, c, rec->t, fn);
      if (unilateral(c) && fn <= 0) {
        if (ap_drv_cm_lift(s, c, rec->t, q) != AP_OK) return -1;
      } else {
        ap_drv_cm_slide_against(s, c, ft);
      }
      break;
    case EV_LIFT:
      if (ap_bm_wheel_by_load(M, c)) return ap_drv_cm_tips(s, c, rec->t, 0.0);
      if (ap_drv_cm_lift(s, c, rec->t, q) != AP_OK) return -1;
      break;
    case EV_STICK:
      ap_cfr_set_mode(M, scratch(s->d), c, AP_CM_ROLLING);   /* settle: slides on if outside */
      break;
    default:
      if (ap_drv_contact_impact(s, e->ci, rec->t, q, v) != AP_OK) return -1;
      bounced = ap_cfr_mode(M, scratch(s->d), c) == AP_CM_AIRBORNE;
      break;
  }
  e->cm->gap0[e->ci] = NAN;
  e->cm->armed[e->ci] = 0;   /* a new mode (a bounce is a new flight): armed again later */
  if (ap_drv_cm_settle(s, rec->t, q, v, &changed, NULL, 1) != AP_OK) return -1;
  if (bounced && ap_cfr_mode(M, scratch(s->d), c) == AP_CM_AIRBORNE)
    e->cm->gap0[e->ci] = ap_contact_gap(M, scratch(s->d), c);   /* the data: at (t, q) */
  return 0;
}

/* At creation: a rolling contact whose sticking force already lies outside its cone slides
 * from the start (along -F_t), one whose normal force is negative flies (unilateral); a wheel
 * under a planar chassis with a negative load stops the run (tips). */
static int initial_cone(ap_sim *s) {
  struct ap_drv_contacts *cm = s->cm;
  double *q = malloc(sizeof(double) * (size_t)(s->n + s->k)), *v = q ? q + s->n : NULL;
  if (!q) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  memcpy(q, s->q, sizeof(double) * (size_t)s->n);
  memcpy(v, s->v, sizeof(double) * (size_t)s->k);
  int changed = 0, rc = ap_drv_cm_settle(s, s->t, q, v, &changed, cm->lifted, 0);
  if (rc == AP_OK && changed) rc = ap_drv_restart_state(s, s->t, q, v);
  if (rc == AP_OK && changed) rc = ap_drv_evaluate_current(s);
  free(q);
  return rc;
}

/* Contact c slides from t0 (slip), or was made airborne at t0 by a negative normal force
 * (lift_off). */
static int at_start(const ap_sim *s, const ap_mcon *c, int kind) {
  int mode = ap_cfr_mode(ap_bm(s->m), scratch(s->d), c);
  return (kind == EV_SLIP && mode == AP_CM_SLIDING) ||
         (kind == EV_LIFT && mode == AP_CM_AIRBORNE && s->cm->lifted[c - ap_bm(s->m)->cons]);
}

int ap_drv_contacts_events(ap_sim *s) {
  struct ap_drv_contacts *cm = s->cm;
  if (!cm) return AP_OK;
  int rc0 = initial_cone(s);
  if (rc0 == AP_OK) rc0 = ap_drv_cm_indeterminate(s);
  if (rc0 != AP_OK) return rc0;
  for (int i = 0; i < cm->nc; i++) {
    const ap_mcon *c = con(s, cm->ci[i]);
    for (int kind = 0; kind < EV_N; kind++) {
      int wanted = kind == EV_SLIP || kind == EV_STICK ? mu_of(c) >= 0 : unilateral(c);
      if (!wanted) continue;
      cm_event *e = &cm->ev[i * EV_N + kind];
      *e = (cm_event){cm, cm->ci[i], kind, ap_drv_event_defined(s)};
      char name[96];
      snprintf(name, sizeof name, "%s.%s", c->name, ev_suffix[kind]);
      ap_event_def def = ap_event_def_default();
      def.name = name, def.fn = value, def.user = e, def.on_switch = on_switch;
      def.direction = AP_EVENT_FALLING, def.action = AP_EVENT_SWITCH;
      def.stage = AP_EVENT_REACTIONS;
      int rc = ap_sim_add_event(s, &def);
      if (rc == AP_OK && at_start(s, c, kind))   /* a switch at t0: recorded like the others */
        rc = ap_drv_event_note(s, ap_drv_event_defined(s) - 1, s->t, -1);
      if (rc != AP_OK) return rc;
    }
  }
  return AP_OK;
}

/* The stage after events, at the accepted state: the slip direction of each sliding contact
 * (the stick event's reference), its stick event armed once |s| > slip_tol, and the airborne
 * contacts' touchdown armed once the gap > gap_tol. */
static void keep_slip(ap_sim *s, const ap_mcon *c) {
  const ap_bmodel *M = ap_bm(s->m);
  double *S = scratch(s->d), sl[2], vmax = 0.0;
  for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(s->d->v[j]));
  ap_cfr_slip(M, S, c, s->d->v, sl);
  double ns = hypot(sl[0], sl[1]), *dir = ap_cfr_slip_dir(M, S, c);
  if (ns > 1e-13 * (1.0 + vmax)) dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
  if (ns > slip_tol(s, s->d->v)) s->cm->armed[c - M->cons] = 1 + AP_CM_SLIDING;
}

int ap_drv_stage_contacts(ap_sim *s, double *t) {
  struct ap_drv_contacts *cm = s->cm;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = scratch(s->d);
  int any = 0;
  for (int i = 0; i < cm->nc; i++) {
    int mode = ap_cfr_mode(M, S, con(s, cm->ci[i]));
    if (!armed(cm, cm->ci[i], mode)) cm->armed[cm->ci[i]] = 0;
    any |= mode == AP_CM_SLIDING || (mode == AP_CM_AIRBORNE && !cm->armed[cm->ci[i]]);
  }
  if (!any) return AP_OK;
  ap_drv_load_state(s, *t, s->dae ? s->ytry : s->y);
  s->ev_stamp = -1;
  int rc = ap_fwd_position(s->m, s->d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", s->d->msg);
  if (s->def.mode == AP_MODE_MINIMAL) ap_core_speeds(s->m, s->d);
  for (int i = 0; i < cm->nc; i++) {
    const ap_mcon *c = con(s, cm->ci[i]);
    int mode = ap_cfr_mode(M, S, c);
    if (mode == AP_CM_SLIDING) keep_slip(s, c);
    if (mode == AP_CM_AIRBORNE && ap_contact_gap(M, S, c) > gap_tol(s))
      cm->armed[c - M->cons] = 1 + AP_CM_AIRBORNE;
  }
  return ap_drv_contacts_watch(s);   /* CVODE BDF's Jacobian (contact_jac.c) */
}

int ap_drv_contacts_switched(ap_sim *s) {
  struct ap_drv_contacts *cm = s->cm;
  const ap_bmodel *M = ap_bm(s->m);
  int changed = 0;
  for (int i = 0; i < cm->nc; i++) {
    char mode = (char)ap_cfr_mode(M, scratch(s->d), con(s, cm->ci[i]));
    changed |= mode != cm->made[cm->ci[i]];
    cm->made[cm->ci[i]] = mode;
  }
  return changed;
}

int ap_sim_contact_mode(const ap_sim *s, int constraint) {
  if (!s || !s->cm || !ap_model_is_body_model(s->m)) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(s->m);
  if (constraint < 0 || constraint >= M->nc || M->cons[constraint].fric < 0) return AP_ERR_ARG;
  return ap_cfr_mode(M, scratch(s->d), &M->cons[constraint]);
}

int ap_drv_cm_note(ap_sim *s, const ap_mcon *c, int from, int to, double t, const double *q,
                   const double *v) {
  struct ap_drv_contacts *cm = s->cm;
  int kind = to == AP_CM_AIRBORNE ? EV_LIFT : from == AP_CM_AIRBORNE ? EV_TOUCH
             : to == AP_CM_SLIDING ? EV_SLIP : EV_STICK;
  for (int i = 0; cm && i < cm->nc; i++) {
    const cm_event *e = &cm->ev[i * EV_N + kind];
    if (cm->ci[i] != (int)(c - ap_bm(s->m)->cons) || !e->cm) continue;
    ap_event_record r;   /* its own crossing tied with this cut is recorded already */
    for (int j = ap_sim_event_count(s) - 1; j >= 0 && ap_sim_event_get(s, j, &r) == AP_OK &&
                                            r.t == t; j--)
      if (r.event == e->idx) return AP_OK;
    return ap_drv_event_note_at(s, e->idx, t, -1, q, v);
  }
  return AP_OK;   /* that event is not watched (a contact without friction never slips) */
}
