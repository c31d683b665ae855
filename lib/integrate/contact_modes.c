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
 *   NAME.lift_off  rolling, sliding: F_n             -> airborne
 *   NAME.stick     sliding:   s . s_ref               -> rolling when the sticking force lies
 *                                                       in the cone, else sliding along -F_t
 *   NAME.touchdown airborne:  the gap                 -> rolling
 * s_ref is the slip direction at the last accepted step (the "contact modes" stage after the
 * events stage keeps it): s . s_ref falls through 0 where the slip speed reaches 0.
 *
 * A switch changes the mode (the rows the model drops) in the data; the driver then restarts
 * the stepper at the event with ap_drv_restart_state, which puts q on the new holonomic rows
 * and v on the new velocity rows nearest in the kinetic-energy metric. At touchdown that
 * projection is the sticking plastic impact v+ = v- - g^-1 A^T (A g^-1 A^T)^-1 (A v- + a0)
 * (ap_impact; Carnot: the energy lost is the kinetic energy of v+ - v-). The number of free
 * speeds changes at a switch: in minimal mode the stepper is created again for the new state
 * size (sim.c). DAE mode is refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "integrate/sim_int.h"
#include "model/con_friction.h"

enum { EV_SLIP, EV_LIFT, EV_STICK, EV_TOUCH, EV_N };
static const char *const ev_suffix[EV_N] = {"slip", "lift_off", "stick", "touchdown"};

typedef struct cm_event {
  struct ap_drv_contacts *cm;
  int ci, kind;
} cm_event;

struct ap_drv_contacts {
  ap_sim *s;
  int nc;            /* contacts with modes */
  int *ci;           /* their constraint index */
  cm_event *ev;      /* EV_N per contact */
};

static const ap_mcon *con(const ap_sim *s, int ci) { return &ap_bm(s->m)->cons[ci]; }
static double *scratch(const ap_data *d) { return ap_bm_scratch(d); }

static double mu_of(const ap_mcon *c) { return c->def.mu; }
static int unilateral(const ap_mcon *c) { return ap_cfr_unilateral(c); }

void ap_drv_contacts_free(ap_sim *s) {
  if (!s->cm) return;
  free(s->cm->ci);
  free(s->cm->ev);
  free(s->cm);
  s->cm = NULL;
}

int ap_drv_contacts_init(ap_sim *s, double t0, const double *q0, const double *v0) {
  if (!ap_model_is_body_model(s->m) || ap_bm(s->m)->nfric == 0) return AP_OK;
  const ap_bmodel *M = ap_bm(s->m);
  if (s->def.mode == AP_MODE_DAE)
    return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "system '%s': contacts with friction or lift-off "
                       "(contact modes) run in minimal, projected and plain modes, not yet in "
                       "DAE mode", s->m->name);
  s->cm = calloc(1, sizeof *s->cm);
  if (s->cm) s->cm->ci = calloc((size_t)M->nfric, sizeof(int));
  if (s->cm && s->cm->ci) s->cm->ev = calloc((size_t)M->nfric * EV_N, sizeof(cm_event));
  if (!s->cm || !s->cm->ci || !s->cm->ev) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
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
static int forces_at(ap_sim *s, double t, const double *q, const double *v) {
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

/* Normal force and tangential force (2) of contact c from the data's multipliers (a wheel
 * under a planar chassis: its load, model/loads.c). */
static double contact_forces(const ap_model *m, const ap_data *d, const ap_mcon *c,
                             double *ft) {
  ft[0] = d->lambda[c->row], ft[1] = d->lambda[c->row + 1];
  return ap_cfr_contact_normal(m, d, d->lambda, c);
}

/* A wheel under a planar chassis cannot leave the ground: the run stops. */
static int tips(ap_sim *s, const ap_mcon *c, double t, double fn) {
  return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "contact '%s': the wheel's load falls to %.6g N at "
                     "t = %.17g: the vehicle would tip or lift that wheel, which a planar "
                     "chassis cannot (its joint keeps the chassis level): put the chassis on a "
                     "free joint (docs/vehicles.md)", c->name, fn, t);
}

static int value(double t, const double *q, const double *v, const ap_data *d, void *user,
                 double *out) {
  const cm_event *e = user;
  const ap_bmodel *M = ap_bm(e->cm->s->m);
  const ap_mcon *c = &M->cons[e->ci];
  double *S = scratch(d), ft[2], sl[2];
  int mode = ap_cfr_mode(M, S, c);
  (void)t, (void)q;
  *out = 1.0;
  switch (e->kind) {
    case EV_SLIP:
      if (mode == AP_CM_ROLLING)
        *out = mu_of(c) * contact_forces(e->cm->s->m, d, c, ft) - hypot(ft[0], ft[1]);
      break;
    case EV_LIFT:
      if (mode != AP_CM_AIRBORNE) *out = contact_forces(e->cm->s->m, d, c, ft);
      break;
    case EV_STICK:
      if (mode == AP_CM_SLIDING) {
        const double *dir = ap_cfr_slip_dir(M, S, c);
        ap_cfr_slip(M, S, c, v, sl);
        *out = sl[0] * dir[0] + sl[1] * dir[1];
      }
      break;
    default:
      if (mode == AP_CM_AIRBORNE) *out = ap_contact_gap(M, S, c);
      break;
  }
  return 0;
}

/* Sliding along -F_t / |F_t| (the sticking force's direction opposes the slip to come). */
static void slide_against(ap_sim *s, const ap_mcon *c, const double *ft) {
  double *dir = ap_cfr_slip_dir(ap_bm(s->m), scratch(s->d), c), nt = hypot(ft[0], ft[1]);
  if (nt > 0) dir[0] = -ft[0] / nt, dir[1] = -ft[1] / nt;
  ap_cfr_set_mode(ap_bm(s->m), scratch(s->d), c, AP_CM_SLIDING);
}

/* Touchdown: the contact's rows back (rolling); the restart's projection is then the sticking
 * plastic impact. With restitution e > 0 the impact is the projection onto the rows with the
 * normal one's target e |vn| instead of 0 (vn < 0 the closing speed of the contact point), in
 * the same metric: a sphere keeps its angular momentum about the contact point and bounces at
 * e |vn|, airborne again; a bounce slower than AP_CM_BOUNCE_MIN (1 + max |v_i|) ends in
 * rolling (plastic), which bounds the number of bounces (e^N |vn| < that speed). */
#define AP_CM_BOUNCE_MIN 1e-6
static int touchdown(ap_sim *s, const ap_mcon *c, double t, const double *q, double *v) {
  const ap_bmodel *M = ap_bm(s->m);
  ap_data *d = s->d;
  double *S = scratch(d), e = c->def.restitution, vn = 0.0, vmax = 0.0;
  ap_cfr_set_mode(M, S, c, AP_CM_ROLLING);
  if (!(e > 0)) return AP_OK;
  ap_basis basis = d->basis;
  int sfe = d->speeds_from_e, r = c->row + c->hrow;
  d->t = t, d->speeds_from_e = 0, d->basis = AP_BASIS_ORTHONORMAL;
  memcpy(d->q, q, sizeof(double) * (size_t)s->n);
  int rc = ap_partition(s->m, d);
  if (rc == AP_OK) rc = ap_fwd_position(s->m, d);
  if (rc == AP_OK) {
    vn = d->a0[r];
    for (int j = 0; j < s->k; j++) vn += d->A[r + (size_t)j * s->b] * v[j];
    for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(v[j]));
  }
  if (rc == AP_OK && -e * vn > AP_CM_BOUNCE_MIN * (1.0 + vmax)) {
    d->a0[r] += e * vn;                 /* A_n v + a0_n = -e vn after the impact */
    rc = ap_core_project_here(s->m, d, v, NULL);
    if (rc == AP_OK) ap_cfr_set_mode(M, S, c, AP_CM_AIRBORNE);
  }
  d->basis = basis, d->speeds_from_e = sfe;
  s->ev_stamp = -1;
  return rc;
}

static int on_switch(const ap_event_record *rec, double *q, double *v, void *user) {
  const cm_event *e = user;
  ap_sim *s = e->cm->s;
  const ap_bmodel *M = ap_bm(s->m);
  const ap_mcon *c = &M->cons[e->ci];
  double *S = scratch(s->d), ft[2], fn;
  switch (e->kind) {
    case EV_SLIP:
      if (forces_at(s, rec->t, q, v) != AP_OK) return -1;
      fn = contact_forces(s->m, s->d, c, ft);
      if (unilateral(c) && fn <= 0 && ap_bm_wheel_by_load(M, c)) return tips(s, c, rec->t, fn);
      if (unilateral(c) && fn <= 0) ap_cfr_set_mode(M, S, c, AP_CM_AIRBORNE);
      else slide_against(s, c, ft);
      break;
    case EV_LIFT:
      if (ap_bm_wheel_by_load(M, c)) return tips(s, c, rec->t, 0.0);
      ap_cfr_set_mode(M, S, c, AP_CM_AIRBORNE);
      break;
    case EV_STICK:
      ap_cfr_set_mode(M, S, c, AP_CM_ROLLING);
      if (forces_at(s, rec->t, q, v) != AP_OK) return -1;
      fn = contact_forces(s->m, s->d, c, ft);
      if (hypot(ft[0], ft[1]) > mu_of(c) * fn) slide_against(s, c, ft);
      break;
    default:
      if (touchdown(s, c, rec->t, q, v) != AP_OK) return -1;
      break;
  }
  return 0;
}

/* At creation: a rolling contact whose sticking force already lies outside its cone slides
 * from the start (along -F_t), one whose normal force is negative flies (unilateral); a wheel
 * under a planar chassis with a negative load stops the run (tips). */
static int initial_cone(ap_sim *s) {
  struct ap_drv_contacts *cm = s->cm;
  const ap_bmodel *M = ap_bm(s->m);
  double *q = malloc(sizeof(double) * (size_t)(s->n + s->k)), *v = q ? q + s->n : NULL, ft[2];
  if (!q) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  memcpy(q, s->q, sizeof(double) * (size_t)s->n);
  memcpy(v, s->v, sizeof(double) * (size_t)s->k);
  int rc = forces_at(s, s->t, q, v), changed = 0;
  for (int i = 0; rc == AP_OK && i < cm->nc; i++) {
    const ap_mcon *c = con(s, cm->ci[i]);
    int mode = ap_cfr_mode(M, scratch(s->d), c);
    double fn = mode == AP_CM_AIRBORNE ? 0.0 : contact_forces(s->m, s->d, c, ft);
    if (unilateral(c) && fn < 0 && ap_bm_wheel_by_load(M, c)) {   /* sliding or rolling */
      rc = tips(s, c, s->t, fn);
      break;
    }
    if (mode != AP_CM_ROLLING) continue;
    if (unilateral(c) && fn < 0) {
      ap_cfr_set_mode(M, scratch(s->d), c, AP_CM_AIRBORNE), changed = 1;
    } else if (mu_of(c) >= 0 && hypot(ft[0], ft[1]) > mu_of(c) * fn) {
      slide_against(s, c, ft), changed = 1;
    }
  }
  if (rc != AP_OK && rc != AP_ERR_UNSUPPORTED)
    rc = ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "initial state: %s", s->d->msg);
  if (rc == AP_OK && changed) rc = ap_drv_restart_state(s, s->t, q, v);
  if (rc == AP_OK && changed) rc = ap_drv_evaluate_current(s);
  free(q);
  return rc;
}

int ap_drv_contacts_events(ap_sim *s) {
  struct ap_drv_contacts *cm = s->cm;
  if (!cm) return AP_OK;
  int rc0 = initial_cone(s);
  if (rc0 != AP_OK) return rc0;
  for (int i = 0; i < cm->nc; i++) {
    const ap_mcon *c = con(s, cm->ci[i]);
    for (int kind = 0; kind < EV_N; kind++) {
      int wanted = kind == EV_SLIP || kind == EV_STICK ? mu_of(c) >= 0 : unilateral(c);
      if (!wanted) continue;
      cm_event *e = &cm->ev[i * EV_N + kind];
      *e = (cm_event){cm, cm->ci[i], kind};
      char name[96];
      snprintf(name, sizeof name, "%s.%s", c->name, ev_suffix[kind]);
      ap_event_def def = ap_event_def_default();
      def.name = name, def.fn = value, def.user = e, def.on_switch = on_switch;
      def.direction = AP_EVENT_FALLING, def.action = AP_EVENT_SWITCH;
      def.stage = AP_EVENT_REACTIONS;
      int rc = ap_sim_add_event(s, &def);
      if (rc != AP_OK) return rc;
    }
  }
  return AP_OK;
}

/* The stage after events: the slip direction of each sliding contact at the accepted state
 * (the stick event's reference). */
int ap_drv_stage_contacts(ap_sim *s, double *t) {
  struct ap_drv_contacts *cm = s->cm;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = scratch(s->d), sl[2], vmax = 0.0;
  int any = 0;
  for (int i = 0; i < cm->nc; i++) any |= ap_cfr_mode(M, S, con(s, cm->ci[i])) == AP_CM_SLIDING;
  if (!any) return AP_OK;
  ap_drv_load_state(s, *t, s->y);
  s->ev_stamp = -1;
  int rc = ap_fwd_position(s->m, s->d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", s->d->msg);
  if (s->def.mode == AP_MODE_MINIMAL) ap_core_speeds(s->m, s->d);
  for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(s->d->v[j]));
  for (int i = 0; i < cm->nc; i++) {
    const ap_mcon *c = con(s, cm->ci[i]);
    if (ap_cfr_mode(M, S, c) != AP_CM_SLIDING) continue;
    ap_cfr_slip(M, S, c, s->d->v, sl);
    double ns = hypot(sl[0], sl[1]), *dir = ap_cfr_slip_dir(M, S, c);
    if (ns > 1e-13 * (1.0 + vmax)) dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
  }
  return AP_OK;
}

int ap_sim_contact_mode(const ap_sim *s, int constraint) {
  if (!s || !s->cm || !ap_model_is_body_model(s->m)) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(s->m);
  if (constraint < 0 || constraint >= M->nc || M->cons[constraint].fric < 0) return AP_ERR_ARG;
  return ap_cfr_mode(M, scratch(s->d), &M->cons[constraint]);
}
