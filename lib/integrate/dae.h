/* Appell DAE integrator (internal): SUNDIALS IDA on (q, v, lambda, mu) with the index-2
 * residual of docs/design.md §1 and GGL rows for implicit holonomic constraints (dae.c). Used by
 * sim.c for AP_MODE_DAE. No SUNDIALS type in this header. */
#ifndef AP_DAE_H
#define AP_DAE_H

#include <stddef.h>

#include "appell/system.h"
#include "integrate/stepper.h"

typedef struct ap_dae ap_dae;

/* y0, yp0: (n + k + b + nphi) consistent values (from the Appell solve; mu = 0), nphi = the
 * model's implicit holonomic rows (0 without ev.phi). The data d is borrowed: the residual
 * writes its position and velocity stages with AP_BASIS_NONE. */
int ap_dae_create(const ap_model *m, ap_data *d, double t0, const double *y0,
                  const double *yp0, const ap_step_opts *o, ap_dae **out, char *msg,
                  size_t msg_len);
/* One internal step, not past tstop; *t and y (n + k + b + nphi) receive the state reached. */
int ap_dae_one(ap_dae *s, double tstop, double *t, double *y);
void ap_dae_stats(const ap_dae *s, ap_step_stats *st);
const char *ap_dae_message(const ap_dae *s);
void ap_dae_free(ap_dae *s);

#endif
