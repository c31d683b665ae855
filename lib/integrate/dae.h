/* Appell DAE integrator (internal): SUNDIALS IDA on (q, v, lambda, mu) with the index-2
 * residual of docs/design.md §1 and GGL rows for implicit holonomic constraints (dae.c). Used by
 * sim.c for AP_MODE_DAE. No SUNDIALS type in this header.
 *
 * Redundant rows. IDA carries multipliers only for the independent rows of A, chosen once at
 * creation from A at (t0, q0) by the row-pivoted QR of A^T that ap_partition uses to find (and
 * name) redundant rows, and likewise for the independent rows of phi (a loop closure written
 * twice); the choice is kept along the motion, and made again (IDA restarted) only when it has
 * degraded (ap_dae_review_rows). Vectors in this interface are always laid out
 * with all rows, y = (q, v, lambda (b), mu (nphi)): the multipliers of dropped rows are ignored
 * on input and returned as 0. Whether the dropped rows
 * are consistent (at t0 and along the motion) is the caller's business: sim.c judges it with
 * ap_partition at t0 and with the orthonormal basis stage after every step, as in the other
 * modes. */
#ifndef AP_DAE_H
#define AP_DAE_H

#include <stddef.h>

#include "appell/system.h"
#include "integrate/stepper.h"

typedef struct ap_dae ap_dae;

/* Forces the multipliers apply besides A_s^T lambda: a sliding contact's Coulomb force
 * -mu_k F_n s^ with F_n its normal row's multiplier (contact_dae.c). After the velocity stage of
 * each residual, fn writes W (k x b, column r: the generalized force per unit multiplier of row
 * r, zero for the rows without one) and may correct d->Q; returns AP_OK or a negative status
 * with d->msg set. The residual then reads F_v = g v' + h - Q - (A_s^T + W_s) lambda. */
typedef struct ap_dae_couple {
  int (*fn)(void *user, ap_data *d, double *W);
  void *user;
  /* Forces that depend on the accelerations and on every multiplier: a sliding wheel's Coulomb
   * force under a planar chassis, -mu_k N s^ with N the wheel's load (model/loads.c), affine in
   * (v', lambda) (dae_loads.c). After fn, `load` writes into F (k) the force at v' = vd (k) and
   * lambda = lam (b, all rows, the dropped ones 0); the residual then reads
   * F_v = g v' + h - Q - (A_s^T + W_s) lambda - F. `lin` writes its derivatives at the data's
   * state: Fv (k x k) in v' and Fl (k x b) in lambda. Both may use work (b + 2 k doubles). NULL
   * (load): none. */
  int (*load)(void *user, ap_data *d, const double *vd, const double *lam, double *F,
              double *work);
  int (*lin)(void *user, ap_data *d, double *Fv, double *Fl, double *work);
} ap_dae_couple;

/* IDA's tolerances are the user's divided by this factor (dae.c: BDF's global error against the
 * Runge-Kutta methods'), but rtol not below min(rtol, 1e-12). */
#define AP_DAE_TOL_FACTOR 10.0
/* The rtol IDA runs at for a requested rtol. */
double ap_dae_rtol(double rtol);

/* y0, yp0: (n + k + b + nphi) values from the Appell solve at t0; only q, v and q', v' are
 * read (lambda is recomputed for the kept rows, mu = 0). nphi = the model's implicit holonomic
 * rows (0 without ev.phi). rank_rtol: the relative rank tolerance of the row choice (as in
 * ap_partition). The data d is borrowed: it must hold the position stage at (t0, q0) on entry,
 * and the residual then writes its position and velocity stages with AP_BASIS_NONE. */
int ap_dae_create(const ap_model *m, ap_data *d, double t0, const double *y0,
                  const double *yp0, const ap_step_opts *o, double rank_rtol,
                  const ap_dae_couple *cp, ap_dae **out, char *msg, size_t msg_len);
/* cp: the multipliers' coupled forces, or NULL (none). */
/* One internal step, not past tout; *t and y (n + k + b + nphi) receive the state reached. A
 * step never stops short of tout by a sliver (it may stop halfway to tout instead). */
int ap_dae_one(ap_dae *s, double tout, double *t, double *y);
/* IDA's current state in y (n + k + b + nphi); right after creation, the initial values with
 * IDA's multipliers. */
void ap_dae_state(const ap_dae *s, double *y);
/* After an accepted step, with the position stage at that state in the data: choose the kept
 * rows again when they have become much worse conditioned than the rows the QR would choose
 * now (rows redundant only where loops and contacts close can change place along the motion).
 * Returns 1 when they changed (the caller must then call ap_dae_restart), 0 when not, or a
 * negative status. */
int ap_dae_review_rows(ap_dae *s, double rank_rtol);
/* Restart IDA at (t, y) (n + k + b + nphi; lambda recomputed for the kept rows, mu = 0) with
 * q' = qdot, v' = vdot (the Appell solve there), first step h0 (0: IDA's choice). The history
 * is lost: BDF starts again at order 1. */
int ap_dae_restart(ap_dae *s, double t, const double *y, const double *qdot, const double *vdot,
                   double h0);
/* The kept constraint rows (ascending, into A's rows); returns their number (<= b). */
int ap_dae_rows(const ap_dae *s, const int **rows);
/* The kept rows of phi (ascending); returns their number (<= nphi). */
int ap_dae_phi_rows(const ap_dae *s, const int **rows);
/* Dense output of the last step (IDAGetDky): q and v at t into y (n + k + b + nphi; the
 * multipliers' entries 0). AP_ERR_ARG when t is outside the last step. */
int ap_dae_dky(ap_dae *s, double t, double *y);
void ap_dae_stats(const ap_dae *s, ap_step_stats *st);
/* Add the counters of `from` (an IDA made before, now replaced) to those of `to`. */
void ap_dae_carry_stats(ap_dae *to, const ap_dae *from);
/* IDA's multipliers at t within the last step into lam (b + nphi, all rows; dropped rows 0):
 * the derivative of the impulses' interpolating polynomial (IDAGetDky of order 1); right after
 * a (re)start, the initial multipliers. */
int ap_dae_multipliers(ap_dae *s, double t, double *lam);
/* IDA's accelerations v' at t within the last step into vd (k): the derivative of v's
 * interpolating polynomial; right after a (re)start, the initial ones (dae_loads.c). */
int ap_dae_accelerations(ap_dae *s, double t, double *vd);
const char *ap_dae_message(const ap_dae *s);
void ap_dae_free(ap_dae *s);

#endif
