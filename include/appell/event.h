/* Appell: events of a simulation.
 *
 * An event is a scalar function e(t, q, v) of the motion. After every accepted step the
 * driver compares its sign with the sign at the previous step; on a change (in the direction
 * asked for) it locates the crossing on the stepper's dense output by root finding and
 * then stops the run there, records it and goes on, or calls a hook that may change the
 * state and restarts the stepper there:
 *
 *   ap_event_def ev = ap_event_def_default();
 *   ev.name = "lean60"; ev.fn = lean_minus_60deg; ev.direction = AP_EVENT_RISING;
 *   ap_sim_add_event(sim, &ev);
 *   int rc = ap_sim_advance(sim, 10.0);  // AP_STOPPED (status.h): ap_sim_time() = event time
 *   ap_event_record r; ap_sim_event_get(sim, ap_sim_event_count(sim) - 1, &r);
 *
 * Rules. An event already zero at the state where it is added does not fire there (its sign
 * is taken from the first state where it is not zero). Several crossings in one step: the
 * first one wins (log events before it are recorded, crossings after it are looked for again
 * in the next steps); crossings at the same time (within 64 ulps) are all reported, in the
 * order of the events. A crossing is located on the dense output to a bracket of 4 ulps of t;
 * the event time is the bracket's right end (the first time at which e has changed sign). A
 * stop or switch then steps again from the last accepted state to that time with the method
 * itself and refines the time on those states, so that the event time and the state there are
 * the method's own (docs/api.md "Events": within 1e-11 relative of the exact time at rtol
 * 1e-12 with every stepper family); a log event's time and state are the dense output's.
 * A scene without events evaluates nothing of this. */
#ifndef APPELL_EVENT_H
#define APPELL_EVENT_H

#include "appell/export.h"
#include "appell/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ap_event_direction {
  AP_EVENT_EITHER = 0,     /* any sign change */
  AP_EVENT_RISING = 1,     /* from negative to positive */
  AP_EVENT_FALLING = -1    /* from positive to negative */
} ap_event_direction;

typedef enum ap_event_action {
  AP_EVENT_STOP = 0,       /* ap_sim_advance returns AP_STOPPED at the event time */
  AP_EVENT_LOG = 1,        /* recorded; the run goes on (the step is not cut) */
  AP_EVENT_SWITCH = 2      /* the hook runs at the event time and may change q and v; the
                              stepper restarts there, keeping its step size */
} ap_event_action;

/* What the data holds when the event function is called (each includes the ones before). */
typedef enum ap_event_stage {
  AP_EVENT_STATE = 0,      /* d->t, d->q, d->v (and in minimal mode the position stage) */
  AP_EVENT_POSITION = 1,   /* + the position stage (g, A, a0, ...) */
  AP_EVENT_ACCELERATION = 2, /* + the whole ap_forward (vdot, qdot) */
  AP_EVENT_REACTIONS = 3   /* + the multipliers lambda (ap_fwd_reactions) */
} ap_event_stage;

/* The event function: *value = e(t, q, v). q (n), v (k) and d describe the same state; d is
 * the simulation's data (read only). Returns 0, or < 0 to stop the run with AP_ERR_CALLBACK.
 * A value that is not finite stops it with AP_ERR_NAN. */
typedef int (*ap_event_fn)(double t, const double *q, const double *v, const ap_data *d,
                           void *user, double *value);

typedef struct ap_event_record ap_event_record;

/* The hook of AP_EVENT_SWITCH, called at the event time with the state there (q (n), v (k),
 * writable). It may change them (a velocity jump, a new mode of the caller's own); the driver
 * then puts them back on the constraints (q onto its manifold, v nearest in g as at creation)
 * and restarts the stepper. Returns 0, or < 0 to stop the run with AP_ERR_CALLBACK. */
typedef int (*ap_event_switch_fn)(const ap_event_record *ev, double *q, double *v, void *user);

typedef struct ap_event_def {
  const char *name;        /* for records and messages (copied); default "event" */
  ap_event_fn fn;          /* required */
  void *user;              /* passed to fn and on_switch; default NULL */
  ap_event_direction direction; /* default AP_EVENT_EITHER */
  ap_event_action action;  /* default AP_EVENT_STOP */
  ap_event_stage stage;    /* default AP_EVENT_STATE */
  ap_event_switch_fn on_switch; /* required with AP_EVENT_SWITCH, else unused */
  int of_time;             /* 1: fn depends on t alone (q, v and d unused), e.g. a jump of a
                              function of t: its next crossing is found ahead of the steps and
                              the stepper lands just before it, so no step straddles it (a
                              jump makes error-controlled steps across it collapse); default 0 */
  int internal_check;      /* set by ap_event_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_event_def;

AP_API ap_event_def ap_event_def_default(void);

struct ap_event_record {
  const char *name;        /* the event's name (owned by the simulation) */
  int event;               /* its index, in the order of ap_sim_add_event */
  double t;                /* event time (s) */
  int direction;           /* +1 the function rose through 0, -1 it fell */
  ap_event_action action;
  int n, k;                /* sizes of q and v */
  const double *q, *v;     /* the state at the event (n, k); owned by the simulation, valid
                              until it is freed */
};

/* Add an event (before or between advances). Its sign is taken at the current state. Returns
 * AP_ERR_ARG (message in ap_sim_message) for a NULL s or def, no fn, a switch without
 * on_switch, or an unknown direction, action or stage; AP_ERR_NOMEM. */
AP_API int ap_sim_add_event(ap_sim *s, const ap_event_def *def);
/* Events recorded so far, in the order they happened (0 when s is NULL). */
AP_API int ap_sim_event_count(const ap_sim *s);
/* Record i (0 <= i < ap_sim_event_count); AP_ERR_ARG when out of range or out is NULL. */
AP_API int ap_sim_event_get(const ap_sim *s, int i, ap_event_record *out);

/* Contact modes (docs/scenes.md "Friction, slip and lift-off"): a rolling contact with a
 * friction coefficient (mu) or unilateral is rolling, sliding or airborne; its switches are
 * events named CONSTRAINT.slip, .stick, .lift_off, .touchdown (AP_EVENT_SWITCH), recorded like
 * any other. */
typedef enum ap_contact_mode {
  AP_CONTACT_ROLLING = 0,  /* no slip, on the ground */
  AP_CONTACT_SLIDING = 1,  /* Coulomb friction -mu_kinetic F_n s/|s| at the contact point */
  AP_CONTACT_AIRBORNE = 2  /* off the ground */
} ap_contact_mode;
/* The current mode of constraint `constraint` (its index in the model); AP_ERR_ARG when s is
 * NULL or the constraint has no contact modes. */
AP_API int ap_sim_contact_mode(const ap_sim *s, int constraint);

#ifdef __cplusplus
}
#endif
#endif
