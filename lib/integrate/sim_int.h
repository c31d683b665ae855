/* Simulation drivers (internal): the ap_sim struct shared by sim.c (creation, advancing,
 * queries), sim_step.c (the right-hand side and the stages of the work after each accepted
 * step, per mode), sim_after.c (those stages as one pipeline, and the DAE mode's) and event.c
 * (events). Functions here carry the prefix ap_drv_. */
#ifndef AP_INTEGRATE_SIM_INT_H
#define AP_INTEGRATE_SIM_INT_H

#include <stddef.h>

#include "appell/sim.h"
#include "core/core.h"
#include "integrate/dae.h"
#include "integrate/stepper.h"

typedef struct ap_sim_events ap_sim_events;   /* event.c */
typedef struct ap_sim_ctrl ap_sim_ctrl;       /* sim_input.c */
typedef struct ap_drv_lrank ap_drv_lrank;     /* sim_rank.c */

/* One stage of the work after an accepted step (sim_after.c). *t is the time of the step's
 * state (s->y for the steppers, s->ytry for IDA); the events stage may move it back to an
 * event. Returns AP_OK, AP_STOPPED (a stop event; the later stages still run) or a failure. */
typedef int (*ap_drv_stage_fn)(ap_sim *s, double *t);
typedef struct ap_drv_stage {
  const char *name;
  ap_drv_stage_fn run;
} ap_drv_stage;
#define AP_DRV_MAX_STAGES 8

struct ap_sim {
  const ap_model *m;
  ap_data *d;
  ap_sim_def def;
  const ap_step_method *meth;
  ap_stepper *st;           /* minimal and projected modes */
  ap_dae *dae;              /* DAE mode */
  int n, k, b, ny;          /* ny = n + l (minimal), n + k (projected), n + k + b (DAE) */
  double t;                 /* time of the last accepted state */
  double *y, *ytry;         /* (n + k + b) stepper state, trial state */
  double *yev, *ydot;       /* (n + k + b) the state of the last successful right-hand side
                               and a derivative carried over a re-partition */
  long ev_stamp;            /* pipeline stage count (d->cnt) right after that evaluation: the
                               data still holds it while the count is unchanged */
  double ev_t;              /* its time */
  int ev_basis;             /* the data's basis (ap_basis) in that evaluation */
  int ev_inputs_old;        /* 1: the inputs changed since (sim_input.c): its position stage
                               still holds, its forces and derivatives do not */
  double growth_cap;        /* minimal mode: a stage whose basis growth exceeds this fails
                               (recoverably): the step went too far on a frozen partition */
  double *q, *v;            /* (n), (k) the state at t as coordinates and speeds */
  double *fail_state;       /* (1 + n + k) t, q, v of the model's last evaluation when an
                               advance failed (ap_sim_failed_state); valid when has_fail */
  int has_fail;
  double *phi;              /* (nphi) DAE mode: scratch for phi(q) after a step */
  int rhs_status;           /* last failure of the right-hand side */
  int rhs_diverged;         /* 1 when that failure was a trial state that is not finite (the
                               step diverged), 0 when a function of the model failed */
  int failed;               /* DAE mode: a check after an IDA step failed; every later advance
                               returns it (IDA has moved past the state kept in y) */
  char rhs_msg[512];
  ap_sim_stats stats;
  char msg[512];
  char warning[1024];       /* redundant rows dropped at t0, then the first condition warning */
  int cond_warned;
  int native_q;             /* CVODE BDF projects q inside its step (ap_drv_proj) */
  double *gn;               /* native_q: Phi_q, Phi_q^T (nphi x n), phi (nphi), work */
  int *gn_iwork;
  ap_sim_poll_fn poll;      /* called before every internal step (ap_sim_set_poll), or NULL */
  void *poll_user;
  const ap_drv_stage *stages[AP_DRV_MAX_STAGES];   /* the after-step pipeline, in order */
  int nstages;
  ap_sim_events *ev;        /* events and their records (event.c); NULL until one is added */
  double *wt;               /* (ny) the stepper's error weights (ap_step_opts.weight): 1, or 0
                               for a coordinate left out of the step-size control
                               (ap_sim_set_uncontrolled, free_coords.c) */
  double t_ahead;           /* the next crossing of an event of t alone, found ahead (the
                               stepper stops at it); INFINITY when none */
  ap_sim_ctrl *ctrl;        /* inputs and controller (sim_input.c); NULL until declared */
  struct ap_drv_contacts *cm; /* contact modes (contact_modes.c); NULL without them */
  ap_drv_lrank *lr;         /* the loop-rank monitor (sim_rank.c); NULL without loops */
};

/* printf into s->msg; returns status. */
int ap_drv_fail(ap_sim *s, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Load y = (q, e') (minimal mode) or (q, v) into the data at time t. */
void ap_drv_load_state(ap_sim *s, double t, const double *y);
/* The stepper's right-hand side (ap_rhs_fn) with user = ap_sim. */
int ap_drv_rhs(double t, const double *y, double *ydot, void *user);
/* CVODE BDF's projection hook (ap_proj_fn), user = ap_sim: q onto its manifold (body models)
 * and, in projected mode, v onto the constraints. */
int ap_drv_proj(double t, const double *y, double *corr, double *err, void *user);
/* Minimal mode: set s->growth_cap for the next step from the basis growth g at its start: a
 * stage beyond max(AP_DRV_GROWTH_CAP x switch_growth, 2 g) fails recoverably. */
#define AP_DRV_GROWTH_CAP 4.0
void ap_drv_growth_cap(ap_sim *s, double g);
/* The after-step pipeline (sim_after.c): choose the stages for the mode (and events), and run
 * them after an accepted step at *t (s->y holds the new state; IDA: s->ytry). May restart
 * the stepper; *t moves back to a stop or switch event. AP_OK, AP_STOPPED or a failure. */
void ap_drv_pipeline_build(ap_sim *s);
int ap_drv_after_step(ap_sim *s, double *t);
/* The stages (sim_step.c; event.c for events). */
int ap_drv_stage_events(ap_sim *s, double *t);
int ap_drv_stage_event_state(ap_sim *s, double *t);
int ap_drv_stage_coordinates(ap_sim *s, double *t);
int ap_drv_stage_partition(ap_sim *s, double *t);
int ap_drv_stage_projection(ap_sim *s, double *t);
int ap_drv_stage_residual(ap_sim *s, double *t);
int ap_drv_stage_redundant(ap_sim *s, double *t);
/* 1 when the data still holds the successful evaluation at exactly (t, y) (sim_step.c). */
int ap_drv_evaluated_at(const ap_sim *s, double t, const double *y);
/* Before the step to t is accepted (its state in s->ytry): rows redundant for every q, when
 * judged at accepted states (judge_at_accepted), judged here with v projected onto the
 * constraints, so that an inconsistency leaves the state as it was; AP_OK when there is
 * nothing to judge. */
int ap_drv_judge_trial(ap_sim *s, double t);
/* Every redundant row's consistency at (t, y), v projected onto the constraints first outside
 * minimal mode; the failure with s->msg set. */
int ap_drv_judge_state(ap_sim *s, double t, const double *y);
/* IDA's first step from (q, v'): IDA's own guess from |y'| is far too small at tight
 * tolerances; the BDF1 local error h^2 |q''| / 2 = rtol |q| + atol at IDA's tolerances
 * (ap_dae_rtol) with q'' ~ N v' from the Appell solve gives it. 0 when v' = 0. */
double ap_drv_dae_h0(const ap_sim *s, const double *q, const double *vdot);
/* Evaluate the whole pipeline at the accepted state so ap_sim_data and q, v describe it. */
int ap_drv_evaluate_current(ap_sim *s);
/* The number of events added to the simulation (event.c). */
int ap_drv_event_defined(const ap_sim *s);
/* Record event i as having crossed (direction) at t with the current state s->q, s->v: a
 * switch made at creation (a contact sliding from t0). */
int ap_drv_event_note(ap_sim *s, int i, double t, int direction);
/* The same with the state (q, v) given: a switch a hook makes besides its own (a contact made
 * consistent at another's switch, contact_settle.c). */
int ap_drv_event_note_at(ap_sim *s, int i, double t, int direction, const double *q,
                         const double *v);
/* Events (event.c): free them with the simulation. */
void ap_drv_events_free(ap_sim *s);
/* The error weights s->wt, all 1 (free_coords.c). */
int ap_drv_weights_create(ap_sim *s, size_t ny);
/* Restart the stepper (or IDA) at (t, q, v) given as coordinates and speeds: q onto its
 * manifold, v onto the constraints nearest in g, the mode's state rebuilt (sim_restart.c). */
int ap_drv_restart_state(ap_sim *s, double t, const double *q, const double *v);
/* sim_restart.c: the state put on the constraints at creation and restart, the stepper or IDA
 * made for it. */
int ap_drv_consistent_coordinates(ap_sim *s, double t0, const double *q0, double *q);
int ap_drv_consistent_speeds(ap_sim *s, double t0, const double *q0, const double *v0,
                              int refuse);
int ap_drv_setup_dae(ap_sim *s);
/* IDA made for (t, y) (the data holds the Appell solve there; yp: ny of scratch). */
int ap_drv_dae_make(ap_sim *s, double t, double *y, double *yp);
int ap_drv_make_stepper(ap_sim *s, double t0);
/* Contact modes (contact_modes.c): the initial modes from (t0, q0, v0) before the state is put
 * on the constraints, their switch events once the stepper exists, the stage that keeps the
 * slip directions after each step, and freeing. Nothing when the model has no contact
 * modes. */
int ap_drv_contacts_init(ap_sim *s, double t0, const double *q0, const double *v0);
int ap_drv_contacts_events(ap_sim *s);
int ap_drv_stage_contacts(ap_sim *s, double *t);
/* The loop-rank monitor (sim_rank.c): chosen at the consistent initial state (nothing without
 * implicit holonomic rows or on the tree path); its stage stops the run where A loses a rank
 * along the motion (a bifurcation of the loops), in every mode. */
int ap_drv_loop_rank_init(ap_sim *s);
int ap_drv_stage_loop_rank(ap_sim *s, double *t);
void ap_drv_loop_rank_free(ap_sim *s);
/* 1 when the data holds the monitor's position stage at exactly (t, y), in the mode's basis. */
int ap_drv_loop_rank_held(const ap_sim *s, double t, const double *y);
/* A failed step close to a rank drop of A is reported as the drop (AP_ERR_RANK); else rc. */
int ap_drv_loop_rank_failed(ap_sim *s, int rc);
void ap_drv_contacts_free(ap_sim *s);
/* DAE mode with contact modes (contact_dae.c): the residual's Coulomb forces of the sliding
 * contacts (ap_dae_couple, user = the ap_sim), and IDA made again at a switch (the kept rows
 * and the number of multipliers change with the modes). */
int ap_drv_dae_coulomb(void *user, ap_data *d, double *W);
int ap_drv_dae_remake(ap_sim *s, double t, double *y);
/* y's (q, v) onto phi = 0 and every row of A before IDA restarts with other kept rows. */
int ap_drv_dae_onto_rows(ap_sim *s, double t, double *y);
/* The coupling for IDA made at the current modes: ap_drv_dae_coulomb, and while a wheel under
 * a planar chassis slides, its Coulomb force with its load (dae_loads.c). */
ap_dae_couple ap_drv_dae_couple(ap_sim *s);
/* IDA's multipliers at t (b + nphi) for the contact events, the rows' reaction split over
 * redundant rows by minimum norm as in the other modes (contact_dae.c); 0 or -1. */
int ap_drv_dae_event_multipliers(ap_sim *s, double t, double *lam);
/* 1 when a contact's mode changed since the last call (contact_modes.c; IDA is made again
 * only then, a restart with the same modes keeps it). */
int ap_drv_contacts_switched(ap_sim *s);
/* Contact impacts (contact_impact.c): the velocity jump at the touchdown of contact ci at
 * (t, q), v in and out, and the contact's mode after it. */
int ap_drv_contact_impact(ap_sim *s, int ci, double t, const double *q, double *v);
/* CVODE BDF: the sliding contacts' slip velocities to the stepper's Jacobian watch
 * (contact_jac.c), from the contact modes' stage at an accepted state. */
int ap_drv_contacts_watch(ap_sim *s);

/* Inputs and controllers (sim_input.c): free them with the simulation; the time the next
 * internal step must stop at, for an advance to tout (events of t alone, controller
 * instants); the controller stage of the pipeline; before an advance, the first controller
 * call and the restart that changed inputs left pending. */
void ap_drv_ctrl_free(ap_sim *s);
double ap_drv_stop_time(const ap_sim *s, double tout);
int ap_drv_stage_controller(ap_sim *s, double *t);
int ap_drv_inputs_before_advance(ap_sim *s);

#endif
