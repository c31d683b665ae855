/* Events of a simulation (include/appell/event.h): the "events" stage of the after-step
 * pipeline (sim_after.c), root finding on the stepper's dense output, and the records.
 *
 * After each accepted step from (t0, y0) to (t1, y1) every event function is evaluated at the new
 * state (from the step's last evaluation when the data still holds it, else after loading the state
 * and running the stages the event asks for). An event whose value at t1 has left the sign it had
 * (sign, the side it was on; a value 0 at t1 counts as a crossing) is located by Illinois-modified
 * regula falsi (root.c, shared with sim_rank.c) on g(t) = e(t, y(t)), y(t) the dense output of the
 * step (dop853's order-7 interpolant, ARKODE's and CVODE's ap_step_dky, IDA's ap_dae_dky), with a
 * bisection whenever a step of the iteration fails to halve the bracket, down to a bracket of 4
 * ulps of t. The crossing time is the bracket's right end: the state there is already on the side
 * entered, so the event never fires twice at one crossing.
 *
 * Then, in time order: crossings in the direction asked for are recorded (the state at the
 * crossing from the dense output) up to the first stop or switch event, and all at that same
 * time (within AP_EV_TIE). A stop or switch cuts the step there: the stepper (or IDA) steps
 * again from the state the "event state" stage kept at the step's start to the event time,
 * with the method itself (the dense output may be of lower order, and the step that crossed
 * may have straddled a kink), and regula falsi on those re-stepped states refines the time
 * (refine); the records at the cut get that state, a switch hook may change it (the state is
 * then put back on the constraints and the stepper restarted), and events that changed side
 * at the cut itself are reported there too. Crossings after the cut are not recorded: their
 * events keep their side and are found again in a later step. Events that did not cross take
 * the sign of their value at the step's end (a value of exactly 0 keeps the old side, so an
 * event that starts at 0 fires only once it has left 0 and crossed back).
 *
 * Events of t alone (of_time): after each step their next crossing within ten step lengths is
 * found by bisection on the function itself, and the driver's next stop time (s->t_ahead) is
 * the bracket's left end, so no step straddles it; at that stop the crossing, a few ulps
 * ahead, is taken as reached (ahead_now) and cut there without a step. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "core/defcheck.h"
#include "integrate/root.h"
#include "integrate/sim_int.h"

#define AP_EV_TIE (64.0 * DBL_EPSILON)   /* relative: crossings this close are simultaneous */
#define AP_EV_ITER 200                   /* root-finding iterations (bisection bounds it) */

typedef struct ev_item {
  ap_event_def def;
  char *name;
  int sign;            /* side at the last accepted state: +1, -1, 0 (not left 0 yet) */
  double last;         /* value there */
  double end;          /* value at the new state */
  double troot;        /* located crossing (when crossed) */
  int crossed;
} ev_item;

struct ap_sim_events {
  int count, cap;
  ev_item *list;
  int stage;           /* the largest stage any event asks for */
  double t_last;       /* time of the last accepted state the signs describe */
  double *ylast;       /* (ny) that state, as the stepper (or IDA) continued from it */
  double *yd;          /* (ny + n + k) dense-output state; q and v at a cut */
  int *sw;             /* (cap) 1 + the switch record of the current cut, by event; 0 none */
  ap_event_record *rec;
  int nrec, caprec;
};

ap_event_def ap_event_def_default(void) {
  ap_event_def def;
  memset(&def, 0, sizeof def);
  def.name = "event";
  def.direction = AP_EVENT_EITHER;
  def.action = AP_EVENT_STOP;
  def.stage = AP_EVENT_STATE;
  def.internal_check = AP_DEF_CHECK;
  return def;
}

/* ---- evaluating ------------------------------------------------------------------------------ */

/* The data at (t, y) (the stepper's or IDA's state) with the stages `stage` asks for; d->q,
 * d->v then hold the coordinates and speeds. */
static int load(ap_sim *s, double t, const double *y, int stage) {
  ap_data *d = s->d;
  ap_basis basis = d->basis;
  int rc = AP_OK;
  if (s->dae) {
    d->t = t, d->speeds_from_e = 0;
    memcpy(d->q, y, sizeof(double) * (size_t)s->n);
    memcpy(d->v, y + s->n, sizeof(double) * (size_t)s->k);
    d->basis = stage >= AP_EVENT_ACCELERATION ? AP_BASIS_ORTHONORMAL : AP_BASIS_NONE;
  } else {
    ap_drv_load_state(s, t, y);
  }
  s->ev_stamp = -1;                               /* the data no longer holds the rhs */
  if (stage >= AP_EVENT_ACCELERATION) {
    rc = ap_forward(s->m, d);
  } else if (stage >= AP_EVENT_POSITION || s->def.mode == AP_MODE_MINIMAL) {
    rc = ap_fwd_position(s->m, d);
    if (rc == AP_OK && s->def.mode == AP_MODE_MINIMAL) ap_core_speeds(s->m, d);
  }
  if (rc == AP_OK && stage >= AP_EVENT_REACTIONS) rc = ap_fwd_reactions(s->m, d);
  d->basis = basis;
  if (rc != AP_OK)
    return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "events at t = %.17g: %s", t, d->msg);
  return AP_OK;
}

/* it's value with the data loaded at t. */
static int value(ap_sim *s, ev_item *it, double t, double *f) {
  const ap_data *d = s->d;
  *f = NAN;
  int rc = it->def.fn(t, d->q, d->v, d, it->def.user, f);
  if (rc < 0)
    return ap_drv_fail(s, AP_ERR_CALLBACK, "event '%s': its function returned %d at t = %.17g",
                       it->name, rc, t);
  if (!isfinite(*f))
    return ap_drv_fail(s, AP_ERR_NAN, "event '%s': its function is %g at t = %.17g", it->name,
                       *f, t);
  return AP_OK;
}

/* Every event's value at the accepted state (t, y) into end. */
static int values_at(ap_sim *s, double t, const double *y) {
  ap_sim_events *ev = s->ev;
  int rc = AP_OK;
  if (s->dae || ev->stage > AP_EVENT_ACCELERATION || !ap_drv_evaluated_at(s, t, y))
    rc = load(s, t, y, ev->stage);
  for (int i = 0; rc == AP_OK && i < ev->count; i++)
    rc = value(s, &ev->list[i], t, &ev->list[i].end);
  return rc;
}

/* The dense output of the last step at t into ev->yd. */
static int dense(ap_sim *s, double t) {
  int rc = s->dae ? ap_dae_dky(s->dae, t, s->ev->yd) : ap_step_dky(s->st, t, s->ev->yd);
  if (rc != AP_OK)
    return ap_drv_fail(s, rc, "events: %s", s->dae ? ap_dae_message(s->dae)
                                                   : ap_step_message(s->st));
  return AP_OK;
}

static int g_at(ap_sim *s, ev_item *it, double t, double *f) {
  int rc = dense(s, t);
  if (rc == AP_OK) rc = load(s, t, s->ev->yd, (int)it->def.stage);
  return rc == AP_OK ? value(s, it, t, f) : rc;
}

/* ---- locating ---------------------------------------------------------------------------------- */

/* g of the event being located (ctx: a located), for the shared root finder. */
typedef struct located {
  ap_sim *s;
  ev_item *it;
} located;

static int g_root(void *ctx, double t, double *g) {
  located *l = ctx;
  return g_at(l->s, l->it, t, g);
}

/* The crossing of it between (ta, it->last) and (tb, it->end) (root.c; a value 0 is on the
 * side entered); the result is the bracket's right end. */
static int locate(ap_sim *s, ev_item *it, double ta, double tb) {
  located l = {s, it};
  return ap_drv_root_locate(g_root, &l, it->sign, AP_ROOT_ZERO_ENTERED, AP_EV_ITER, ta,
                            it->last, tb, it->end, &it->troot);
}

/* ---- recording ---------------------------------------------------------------------------------- */

static int record(ap_sim *s, int i, double t, int dir, ap_event_record **out) {
  ap_sim_events *ev = s->ev;
  if (ev->nrec == ev->caprec) {
    int cap = ev->caprec ? 2 * ev->caprec : 8;
    ap_event_record *r = realloc(ev->rec, sizeof *r * (size_t)cap);
    if (!r) return ap_drv_fail(s, AP_ERR_NOMEM, "events: out of memory");
    ev->rec = r, ev->caprec = cap;
  }
  double *x = malloc(sizeof(double) * (size_t)(s->n + s->k));
  if (!x) return ap_drv_fail(s, AP_ERR_NOMEM, "events: out of memory");
  memcpy(x, s->d->q, sizeof(double) * (size_t)s->n);
  memcpy(x + s->n, s->d->v, sizeof(double) * (size_t)s->k);
  ap_event_record *r = &ev->rec[ev->nrec++];
  *r = (ap_event_record){ev->list[i].name, i, t, dir, ev->list[i].def.action, s->n, s->k, x,
                         x + s->n};
  *out = r;
  return AP_OK;
}

/* Crossing i fires: direction matches. */
static int fires(const ev_item *it) {
  int dir = -it->sign;   /* +1: rose through 0 */
  return it->def.direction == AP_EVENT_EITHER || (int)it->def.direction == dir;
}

/* The earliest crossing not yet handled at or before tmax, or -1. */
static int next_crossing(const ap_sim_events *ev, double tmax) {
  int best = -1;
  for (int i = 0; i < ev->count; i++)
    if (ev->list[i].crossed == 1 && ev->list[i].troot <= tmax &&
        (best < 0 || ev->list[i].troot < ev->list[best].troot))
      best = i;
  return best;
}

/* The first stop or switch crossing (its time, INFINITY when none, in *tc). */
static int first_cut(const ap_sim_events *ev, double *tc) {
  int best = -1;
  *tc = INFINITY;
  for (int i = 0; i < ev->count; i++) {
    const ev_item *it = &ev->list[i];
    if (it->crossed && fires(it) && it->def.action != AP_EVENT_LOG && it->troot < *tc)
      *tc = it->troot, best = i;
  }
  return best;
}

/* Record the crossings up to tcut (and those tied with it) in time order; flip their sides.
 * *cut: the switch record at the cut (or the last record at it). */
static int record_crossings(ap_sim *s, double tcut, double t1, int *stop, int *sw) {
  ap_sim_events *ev = s->ev;
  double tmax = isfinite(tcut) ? tcut + AP_EV_TIE * fmax(fabs(tcut), t1 - ev->t_last) : t1;
  for (int i; (i = next_crossing(ev, tmax)) >= 0;) {
    ev_item *it = &ev->list[i];
    it->crossed = 2;
    if (fires(it)) {
      double t = isfinite(tcut) && it->troot > tcut ? tcut : it->troot;
      ap_event_record *r = NULL;
      int rc = dense(s, fmin(t, t1));   /* a crossing found ahead: the state at t1 */
      if (rc == AP_OK) rc = load(s, t, ev->yd, AP_EVENT_STATE);
      if (rc == AP_OK) rc = record(s, i, t, -it->sign, &r);
      if (rc != AP_OK) return rc;
      if (it->def.action == AP_EVENT_STOP) *stop = 1;
      if (it->def.action == AP_EVENT_SWITCH) sw[i] = ev->nrec;
    }
    it->sign = -it->sign;
  }
  return AP_OK;
}

/* Step again from the last accepted state to tcut, with the stepper itself, so that the state
 * at a cut is the method's own, not the dense output's: the step that crossed may have
 * straddled a kink, and ARKODE's interpolant is of lower order than its methods. IDA's dense
 * output is its own BDF polynomial of the step, so DAE mode takes the state there (IDA keeps
 * the step until cut_at restarts it at the cut): stepping again from the step's start restarted
 * BDF at order 1, and at each of refine's iterations IDA crossed the whole step again in
 * order-1 and -2 steps (campaign seed 1001158: 270 steps of 1e-6 s each time, four times
 * over a step of 3.8e-4 s, where the step itself was one). */
static int restep(ap_sim *s, double tcut) {
  ap_sim_events *ev = s->ev;
  double t = ev->t_last;
  int rc;
  s->stats.restarts++;
  if (s->dae) {
    /* a cut a few ulps after the step's start is the start */
    if (!(tcut - t > 32.0 * DBL_EPSILON * fabs(tcut))) {
      memcpy(s->ytry, ev->ylast, sizeof(double) * (size_t)s->ny);
      return AP_OK;
    }
    rc = ap_dae_dky(s->dae, tcut, s->ytry);
    return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "events: %s", ap_dae_message(s->dae));
  }
  memcpy(s->y, ev->ylast, sizeof(double) * (size_t)s->ny);
  rc = ap_step_reset(s->st, t, s->y);
  /* a step may end a few ulps short of tcut, where no step fits: the state is then tcut's */
  while (rc == AP_OK && tcut - t > 32.0 * DBL_EPSILON * fabs(tcut))
    rc = ap_step_one(s->st, tcut, &t, s->y);
  if (rc == AP_OK && t != tcut) rc = ap_step_reset(s->st, tcut, s->y);
  if (rc != AP_OK)
    return ap_drv_fail(s, rc, "events: stepping again to t = %.17g: %s", tcut,
                       ap_step_message(s->st));
  return AP_OK;
}

/* After stepping again to *t, the cut event's value on the method's own state: when it is not
 * 0 yet, regula falsi steps (each stepping again from the last accepted state) on the bracket
 * it leaves with the step's start or end, while they move t by more than 4 ulps (at most 3:
 * the dense output's time is already close, and each step about squares its error). */
static int refine(ap_sim *s, ev_item *it, double *t, double t1) {
  double ta = s->ev->t_last, ga = it->last, tb = t1, gb = it->end, tc = *t, gc = 0.0;
  for (int iter = 0; iter < 3; iter++) {
    int rc = load(s, tc, s->dae ? s->ytry : s->y, (int)it->def.stage);
    if (rc == AP_OK) rc = value(s, it, tc, &gc);
    if (rc != AP_OK || gc == 0.0) return rc;
    if (gc * it->sign < 0) ta = tc, ga = gc;   /* still on the old side (sign: the new one) */
    else tb = tc, gb = gc;
    double tn = tb - gb * (tb - ta) / (gb - ga);
    if (!(tn > ta && tn < tb) || fabs(tn - tc) <= 4.0 * DBL_EPSILON * fabs(tc)) return AP_OK;
    if ((rc = restep(s, tn)) != AP_OK) return rc;
    *t = tc = tn;
  }
  return AP_OK;
}

/* Cut the step at *t < t1 (or at t1 for a switch): the state there (the time refined on it),
 * the records made at the cut (from first on) moved to it, the switch hooks, and the
 * restart. */
static int cut_at(ap_sim *s, double *tp, double t1, const int *sw, int first, ev_item *cut) {
  ap_sim_events *ev = s->ev;
  double *q = ev->yd + s->ny, *v = q + s->n, t0 = *tp;
  int rc = t0 < t1 ? restep(s, t0) : AP_OK, hooked = 0;
  if (rc == AP_OK && t0 < t1) rc = refine(s, cut, tp, t1);
  double t = *tp;
  if (rc == AP_OK) rc = load(s, t, s->dae ? s->ytry : s->y, AP_EVENT_STATE);
  if (rc != AP_OK) return rc;
  memcpy(q, s->d->q, sizeof(double) * (size_t)s->n);
  memcpy(v, s->d->v, sizeof(double) * (size_t)s->k);
  for (int r = first; r < ev->nrec; r++) {
    if (ev->rec[r].t != t0) continue;
    ev->rec[r].t = t;
    memcpy((double *)ev->rec[r].q, q, sizeof(double) * (size_t)s->n);
    memcpy((double *)ev->rec[r].v, v, sizeof(double) * (size_t)s->k);
  }
  for (int i = 0; i < ev->count; i++) {
    if (!sw[i]) continue;
    hooked = 1;
    char why[sizeof s->msg];            /* a hook of the library's (contact modes) may say why */
    memcpy(why, s->msg, sizeof s->msg);
    s->msg[0] = '\0';
    if (ev->list[i].def.on_switch(&ev->rec[sw[i] - 1], q, v, ev->list[i].def.user) < 0)
      return s->msg[0] ? AP_ERR_UNSUPPORTED   /* the hook said why (ap_drv_fail) */
                       : ap_drv_fail(s, AP_ERR_CALLBACK, "event '%s': its switch hook failed "
                                     "at t = %.17g", ev->list[i].name, t);
    if (!s->msg[0]) memcpy(s->msg, why, sizeof s->msg);
  }
  /* DAE mode: IDA still holds the step that crossed (restep) */
  return hooked || (s->dae && t0 < t1) ? ap_drv_restart_state(s, t, q, v) : AP_OK;
}

/* After a cut at t: events that changed side at the cut itself (a function that jumps where a
 * kink of t is, e.g. a motor's saturation at its set-point's jump) are crossings at t too. */
static int jumped_at_cut(ap_sim *s, double t, int *stop) {
  ap_sim_events *ev = s->ev;
  for (int i = 0; i < ev->count; i++) {
    ev_item *it = &ev->list[i];
    if (it->crossed || it->sign == 0 || !(it->end * it->sign < 0)) continue;
    ap_event_record *r = NULL;
    if (fires(it)) {
      int rc = load(s, t, s->dae ? s->ytry : s->y, AP_EVENT_STATE);
      if (rc == AP_OK) rc = record(s, i, t, -it->sign, &r);
      if (rc != AP_OK) return rc;
      if (it->def.action == AP_EVENT_STOP) *stop = 1;
    }
    it->sign = -it->sign, it->crossed = 1;
  }
  return AP_OK;
}

/* Signs and values from ev->list[].end at the state the step ends (or was cut) at. */
static void settle(ap_sim_events *ev) {
  for (int i = 0; i < ev->count; i++) {
    ev_item *it = &ev->list[i];
    if (!it->crossed && it->end != 0.0) it->sign = it->end > 0 ? 1 : -1;
    it->last = it->end;
    it->crossed = 0;
  }
}

/* The last stage: the state the next step starts from (after projections, re-partitions). */
int ap_drv_stage_event_state(ap_sim *s, double *t) {
  memcpy(s->ev->ylast, s->dae ? s->ytry : s->y, sizeof(double) * (size_t)s->ny);
  s->ev->t_last = *t;
  return AP_OK;
}

/* Events of t alone: the crossing of `it` in (t, t + H], H = 10 x the last step (steps
 * grow by at most 6), by bisection on fn (exact: no state); INFINITY when none. The stepper
 * stops at the bracket's left end (still on the old side), and the stage then takes the
 * crossing a few ulps ahead as reached (ahead_now). */
static double ahead(ap_sim *s, ev_item *it, double t, double h, double *right) {
  double ta = t, tb = t + 10.0 * h, gb = 0.0;
  if (!(h > 0) || it->sign == 0 || it->def.fn(tb, s->d->q, s->d->v, s->d, it->def.user, &gb) < 0 ||
      !(gb * it->sign <= 0))
    return INFINITY;
  while (tb - ta > 4.0 * DBL_EPSILON * fabs(tb)) {
    double tm = 0.5 * (ta + tb), gm = 0.0;
    if (it->def.fn(tm, s->d->q, s->d->v, s->d, it->def.user, &gm) < 0) return INFINITY;
    if (gm * it->sign > 0) ta = tm;
    else tb = tm;
  }
  *right = tb;
  return ta;
}

/* Events of t alone whose crossing the stepper stopped just before: reached now. */
static void ahead_now(ap_sim *s, double t1) {
  ap_sim_events *ev = s->ev;
  for (int i = 0; i < ev->count; i++) {
    ev_item *it = &ev->list[i];
    if (it->def.of_time && !it->crossed && isfinite(it->troot) && it->troot > t1 &&
        it->troot - t1 <= 64.0 * DBL_EPSILON * fabs(t1))
      it->crossed = 1;
  }
}

/* After the stage: the next crossing ahead of any event of t alone. */
static void look_ahead(ap_sim *s, double t, double h) {
  ap_sim_events *ev = s->ev;
  s->t_ahead = INFINITY;
  for (int i = 0; i < ev->count; i++) {
    ev_item *it = &ev->list[i];
    double right = INFINITY, left = it->def.of_time ? ahead(s, it, t, h, &right) : INFINITY;
    it->troot = right;
    /* a crossing a few ulps ahead that did not cut (a log event): the next step passes it
     * and finds it as any other; stopping there again would not move */
    if (left - t > 64.0 * DBL_EPSILON * fabs(t)) s->t_ahead = fmin(s->t_ahead, left);
  }
}

int ap_drv_stage_events(ap_sim *s, double *t) {
  ap_sim_events *ev = s->ev;
  double t1 = *t, *y = s->dae ? s->ytry : s->y, h = t1 - ev->t_last;
  int rc = values_at(s, t1, y), any = 0, stop = 0;
  for (int i = 0; rc == AP_OK && i < ev->count; i++) {
    ev_item *it = &ev->list[i];
    it->crossed = it->sign != 0 && (it->end == 0.0 || (it->end > 0) != (it->sign > 0));
    if (it->crossed) rc = locate(s, it, ev->t_last, t1);
    any |= it->crossed;
  }
  if (rc == AP_OK && s->t_ahead <= t1) {
    ahead_now(s, t1);
    for (int i = 0; i < ev->count; i++) any |= ev->list[i].crossed;
  }
  if (rc != AP_OK || !any) {
    if (rc == AP_OK) settle(ev), look_ahead(s, t1, h);
    return rc;
  }
  int *sw = ev->sw, first = ev->nrec, hooked = 0;
  memset(sw, 0, sizeof *sw * (size_t)ev->count);
  double tcut;
  int ic = first_cut(ev, &tcut);
  rc = record_crossings(s, tcut, t1, &stop, sw);
  for (int i = 0; i < ev->count; i++) hooked |= sw[i] != 0;
  if (rc == AP_OK && isfinite(tcut)) {
    if (tcut < t1 || hooked) rc = cut_at(s, &tcut, t1, sw, first, &ev->list[ic]);
    *t = tcut;
    if (rc == AP_OK) rc = values_at(s, *t, s->dae ? s->ytry : s->y);
  }
  for (int i = 0; i < ev->count; i++) ev->list[i].crossed = ev->list[i].crossed == 2;
  if (rc == AP_OK && isfinite(tcut)) rc = jumped_at_cut(s, *t, &stop);
  /* a falling switch whose hook put its value above 0 again watches its next fall from the
   * cut on (a bouncing contact's touchdown: keeping the crossed side missed the next
   * touchdown when one step spanned the whole bounce) */
  for (int i = 0; rc == AP_OK && i < ev->count; i++)
    if (sw[i] && ev->list[i].def.direction == AP_EVENT_FALLING && ev->list[i].end > 0.0)
      ev->list[i].crossed = 0;
  if (rc == AP_OK) settle(ev), look_ahead(s, *t, h);
  return rc != AP_OK ? rc : stop ? AP_STOPPED : AP_OK;
}

/* ---- the public functions ------------------------------------------------------------------------- */

static int check_event(ap_sim *s, const ap_event_def *def) {
  if (!def || !def->fn)
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_add_event: %s", def ? "no event function (fn)"
                                                                  : "NULL definition");
  const char *name = def->name ? def->name : "event";
  if (def->internal_check != AP_DEF_CHECK)
    return ap_drv_fail(s, AP_ERR_ARG, "ap_event_def '%s' " AP_DEF_NOT_DEFAULT("ap_event_def"),
                       name);
  if (def->direction < AP_EVENT_FALLING || def->direction > AP_EVENT_RISING)
    return ap_drv_fail(s, AP_ERR_ARG, "event '%s': unknown direction %d", name,
                       (int)def->direction);
  if (def->action < AP_EVENT_STOP || def->action > AP_EVENT_SWITCH)
    return ap_drv_fail(s, AP_ERR_ARG, "event '%s': unknown action %d", name, (int)def->action);
  if (def->stage < AP_EVENT_STATE || def->stage > AP_EVENT_REACTIONS)
    return ap_drv_fail(s, AP_ERR_ARG, "event '%s': unknown stage %d", name, (int)def->stage);
  if (def->action == AP_EVENT_SWITCH && !def->on_switch)
    return ap_drv_fail(s, AP_ERR_ARG, "event '%s': a switch needs a hook (on_switch)", name);
  return AP_OK;
}

static int grow(ap_sim *s) {
  if (!s->ev) {
    s->ev = calloc(1, sizeof *s->ev);
    size_t ny = (size_t)(s->n + s->k + s->b + (s->m->ev.phi ? s->m->nphi : 0));
    if (s->ev) s->ev->yd = calloc(2 * ny + (size_t)(s->n + s->k), sizeof(double));
    if (!s->ev || !s->ev->yd) return ap_drv_fail(s, AP_ERR_NOMEM, "events: out of memory");
    s->ev->ylast = s->ev->yd + ny + s->n + s->k;
    s->ev->t_last = s->t;
    memcpy(s->ev->ylast, s->y, sizeof(double) * (size_t)s->ny);
  }
  ap_sim_events *ev = s->ev;
  if (ev->count < ev->cap) return AP_OK;
  int cap = ev->cap ? 2 * ev->cap : 4;
  ev_item *l = realloc(ev->list, sizeof *l * (size_t)cap);
  if (l) ev->list = l;
  int *sw = l ? realloc(ev->sw, sizeof *sw * (size_t)cap) : NULL;
  if (!sw) return ap_drv_fail(s, AP_ERR_NOMEM, "events: out of memory");
  ev->sw = sw, ev->cap = cap;
  return AP_OK;
}

int ap_sim_add_event(ap_sim *s, const ap_event_def *def) {
  if (!s) return AP_ERR_ARG;
  int rc = check_event(s, def);
  if (rc == AP_OK) rc = grow(s);
  if (rc != AP_OK) return rc;
  ap_sim_events *ev = s->ev;
  ev_item *it = &ev->list[ev->count];
  memset(it, 0, sizeof *it);
  it->def = *def;
  const char *name = def->name ? def->name : "event";
  it->name = malloc(strlen(name) + 1);
  if (!it->name) return ap_drv_fail(s, AP_ERR_NOMEM, "events: out of memory");
  strcpy(it->name, name);
  double *y = s->y;                              /* the current state (IDA's too) */
  rc = load(s, s->t, y, (int)def->stage);
  if (rc == AP_OK) rc = value(s, it, s->t, &it->last);
  if (rc == AP_OK) rc = ap_drv_evaluate_current(s);   /* the data back at the current state */
  if (rc != AP_OK) return free(it->name), rc;
  it->sign = it->last > 0 ? 1 : it->last < 0 ? -1 : 0;
  ev->count++;
  if ((int)def->stage > ev->stage) ev->stage = (int)def->stage;
  ev->t_last = s->t;
  memcpy(ev->ylast, s->y, sizeof(double) * (size_t)s->ny);
  ap_drv_pipeline_build(s);
  return AP_OK;
}

int ap_sim_event_count(const ap_sim *s) { return s && s->ev ? s->ev->nrec : 0; }

int ap_sim_event_get(const ap_sim *s, int i, ap_event_record *out) {
  if (!s || !out || i < 0 || i >= ap_sim_event_count(s)) return AP_ERR_ARG;
  *out = s->ev->rec[i];
  return AP_OK;
}

void ap_drv_events_free(ap_sim *s) {
  ap_sim_events *ev = s->ev;
  if (!ev) return;
  for (int i = 0; i < ev->count; i++) free(ev->list[i].name);
  for (int i = 0; i < ev->nrec; i++) free((double *)ev->rec[i].q);
  free(ev->list);
  free(ev->sw);
  free(ev->rec);
  free(ev->yd);
  free(ev);
  s->ev = NULL;
}

int ap_drv_event_defined(const ap_sim *s) { return s->ev ? s->ev->count : 0; }

int ap_drv_event_note(ap_sim *s, int i, double t, int direction) {
  return ap_drv_event_note_at(s, i, t, direction, s->q, s->v);   /* the current state */
}

int ap_drv_event_note_at(ap_sim *s, int i, double t, int direction, const double *q,
                         const double *v) {
  if (!s->ev || i < 0 || i >= s->ev->count) return AP_ERR_ARG;
  ap_event_record *r = NULL;
  memmove(s->d->q, q, sizeof(double) * (size_t)s->n);
  memmove(s->d->v, v, sizeof(double) * (size_t)s->k);
  return record(s, i, t, direction, &r);
}
