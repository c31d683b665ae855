/* Contact modes inside the driver (internal to lib/integrate): the helpers contact_modes.c
 * shares with contact_settle.c. */
#ifndef AP_INTEGRATE_CONTACT_INT_H
#define AP_INTEGRATE_CONTACT_INT_H

#include "integrate/sim_int.h"
#include "model/con_friction.h"

/* The data at (t, q, v) with accelerations and multipliers for the current modes
 * (orthonormal basis, the mode's basis restored). */
int ap_drv_cm_forces(ap_sim *s, double t, const double *q, const double *v);
/* F_n and F_t (2) of contact c from the multipliers lam. */
double ap_drv_cm_normal(const ap_sim *s, const double *lam, const ap_mcon *c, double *ft);
/* DAE mode: F_n and F_t (2) of contact c at t from IDA's multipliers lam; a wheel under a
 * planar chassis, its load at IDA's own accelerations (into vd, k) and lam (dae_loads.c). NaN
 * when they cannot be evaluated. */
double ap_drv_dae_cm_normal(ap_sim *s, double t, const double *lam, const ap_mcon *c,
                            double *vd, double *ft);
/* Contact c slides along -F_t / |F_t|. */
void ap_drv_cm_slide_against(ap_sim *s, const ap_mcon *c, const double *ft);
/* Contact c flies from (t, q): q onto the current modes' manifold first (q in and out). */
int ap_drv_cm_lift(ap_sim *s, const ap_mcon *c, double t, double *q);
/* A wheel under a planar chassis whose load falls to fn: the run stops (its status). */
int ap_drv_cm_tips(ap_sim *s, const ap_mcon *c, double t, double fn);
/* 1 while sliding contact c's slip has not exceeded slip_tol at an accepted step since it
 * began (its stick event not yet armed). */
int ap_drv_cm_slip_young(const ap_sim *s, const ap_mcon *c);

/* F_t (2, in place) of rolling contact c less the share that rows without a friction limit
 * can carry (its tangential rows' combinations in their span; contact_share.c), from the
 * data's A; the scratch it uses ((b + 2) k doubles, NULL when the run has no modes). */
void ap_drv_cm_determinate(ap_sim *s, const ap_mcon *c, double *ft);
double *ap_drv_cm_share_scratch(ap_sim *s);

/* The run's warning names each rolling contact whose friction is statically indeterminate
 * at the start (its tangential rows combinations of the others; contact_indet.c). */
int ap_drv_cm_indeterminate(ap_sim *s);

/* Record contact c's switch from mode `from` to `to` at (t, q, v) as the event of that
 * switch (NAME.slip, .stick, .lift_off, .touchdown), a switch made by another's hook. */
int ap_drv_cm_note(ap_sim *s, const ap_mcon *c, int from, int to, double t, const double *q,
                   const double *v);

/* The consistent modes at a switch state (contact_settle.c), v put on the modes' velocity
 * rows (nearest in g) first, as the restart after it would: each contact's mode is checked
 * against the forces and accelerations it gives and changed while one of them clearly
 * contradicts it (F_n < 0 rolling or sliding; |F_t| > mu F_n rolling; an airborne contact
 * touching the ground whose gap would fall). *changed: 1 when a mode changed; contact
 * `lifted` (by constraint index, may be NULL) marks the contacts made airborne. A cycle of
 * modes stops the run with a message (no consistent mode: Painleve). With `note`, each change
 * is recorded as its switch event (ap_drv_cm_note). */
int ap_drv_cm_settle(ap_sim *s, double t, double *q, double *v, int *changed, char *lifted,
                     int note);

#endif
