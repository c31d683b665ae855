/* Appell body layer (internal): contact modes of rolling contacts (con_friction.c).
 *
 * A rolling contact with def.mu >= 0 or def.unilateral (a body not on a plane-contact joint:
 * rows .x, .y, the contact row .z) is in one of three modes, held per data in the model's
 * "contact modes" scratch block (zero-filled at creation: rolling):
 *   rolling   every row active (the model of a contact without modes);
 *   sliding   the no-slip rows (.x, .y, .spin) are zero rows, and the Coulomb force
 *             -mu_kinetic F_n s/|s| acts at the contact point, F_n the .z row's multiplier
 *             solved with the accelerations (ap_cfr_friction);
 *   airborne  every row of the contact is a zero row, its holonomic row is closed (0).
 * Zero rows are redundant rows to the core (dropped, consistent: a0 = gamma = 0), so the
 * partition, the projections and the reactions need no other change. Double build only; the
 * contact's rows, gamma and holonomic row call these after writing their own values. */
#ifndef AP_MODEL_CON_FRICTION_H
#define AP_MODEL_CON_FRICTION_H

#include "model/model.h"

enum { AP_CM_ROLLING = 0, AP_CM_SLIDING = 1, AP_CM_AIRBORNE = 2 };

/* The mode of contact c (c->fric >= 0) in the data whose body scratch is S. */
int ap_cfr_mode(const ap_bmodel *M, const double *S, const ap_mcon *c);
void ap_cfr_set_mode(const ap_bmodel *M, double *S, const ap_mcon *c, int mode);
/* The slip direction (tangent coordinates, 2) taken while |s| is 0; set by the driver. */
double *ap_cfr_slip_dir(const ap_bmodel *M, double *S, const ap_mcon *c);
/* F_n of a sliding contact at the last evaluation (N). */
double ap_cfr_normal_force(const ap_bmodel *M, const double *S, const ap_mcon *c);
/* After the contact wrote its rows: keep its tangent rows (the slip velocity s_i = A_i v +
 * a0_i), then zero the rows its mode drops. */
void ap_cfr_rows(const ap_bmodel *M, double *S, const ap_mcon *c, double *A, double *a0);
void ap_cfr_gamma(const ap_bmodel *M, const double *S, const ap_mcon *c, double *gamma);
/* The slip velocity (tangent coordinates, 2) at the data's v from the kept tangent rows. */
void ap_cfr_slip(const ap_bmodel *M, double *S, const ap_mcon *c, const double *v, double *s);
/* Sliding contacts: F_n solved with the accelerations and the Coulomb force added to Q (at the
 * end of the velocity stage, Q, h, gamma and the position stage complete). AP_ERR_SINGULAR
 * with a message when the normal forces have no unique solution (Painleve). */
int ap_cfr_friction(const ap_model *m, ap_data *d, double *S);
/* A sliding contact's Coulomb force -mu_k fn s^ (s^ of the last evaluation, tangents t1, t2)
 * added to F (3; with t1 NULL: to F (2) in tangent coordinates); nothing in the other modes. */
void ap_cfr_friction_force(const ap_bmodel *M, const double *S, const ap_mcon *c, double fn,
                           const double *t1, const double *t2, double *F);
/* The normal force of contact c at the data's state after the reactions (v', multipliers lam
 * (b)): its row .z's multiplier, or under a planar chassis the wheel's load (model/loads.c);
 * NaN when the load cannot be evaluated. */
double ap_cfr_contact_normal(const ap_model *m, const ap_data *d, const double *lam,
                             const ap_mcon *c);
/* Sliding contact c: its Coulomb force per unit normal force as a generalized force (k),
 * f = -mu_k T^T s^ (the tangent rows T and the direction s^ of the last evaluation): the
 * friction term ap_cfr_friction adds to Q is f F_n. */
void ap_cfr_coulomb(const ap_bmodel *M, const double *S, const ap_mcon *c, double *f);
/* 1 when contact c lifts off (def.unilateral, or by default when it has a friction coefficient). */
int ap_cfr_unilateral(const ap_mcon *c);
/* The gap of contact c whatever its mode (m; contact.c), after the position stage. */
double ap_contact_gap(const ap_bmodel *M, double *S, const ap_mcon *c);
double ap_contact_gap_rate(const ap_bmodel *M, double *S, const ap_mcon *c, const double *v,
                           double *rate);

#endif
