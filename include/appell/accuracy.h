/* Appell: accuracy on demand (docs/accuracy.md).
 *
 * - The global error of a run on its output channels, estimated a posteriori by a second run
 *   at a tighter tolerance on the same output times (ap_global_error).
 * - The method and tolerances that reach a requested global error at the least cost, chosen
 *   from a short pilot (ap_accuracy_pick).
 * - Error control where it matters: coordinates nothing else depends on (a ball's orientation
 *   on a turntable) can be left out of the step-size control (ap_sim_free_coordinates,
 *   ap_sim_set_uncontrolled); their error is then not controlled, and reported so.
 *
 * Units: an error is in the units of its output channel (m, rad, m/s, ...). The error of a run
 * is one number: the largest over channels and output times of |x - x_ref| / max(1, scale),
 * scale being the channel's largest magnitude on the reference run (absolute error for
 * channels of size up to 1, relative error for larger ones). */
#ifndef APPELL_ACCURACY_H
#define APPELL_ACCURACY_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- error control where it matters ---------------------------------------------------- */

/* free_ (n) receives 1 for each coordinate that no other part of the state's derivative
 * depends on (found numerically at the current state and a nearby one; docs/accuracy.md),
 * 0 otherwise; all 0 once an event has been added (an event may read any coordinate).
 * Outputs are not considered: clear the flags of the coordinates they
 * ask for before ap_sim_set_uncontrolled. AP_ERR_ARG for NULL, AP_ERR_UNSUPPORTED in DAE
 * mode. */
AP_API int ap_sim_free_coordinates(ap_sim *s, int *free_);
/* Leave the coordinates flagged in flags (n; NULL = none) out of the step-size control from
 * the next step on (their error weight becomes 0); every other coordinate and every speed
 * stays controlled. AP_ERR_ARG for a NULL s, AP_ERR_UNSUPPORTED in DAE mode. Default: every
 * coordinate controlled. */
AP_API int ap_sim_set_uncontrolled(ap_sim *s, const int *flags);
/* 1 when coordinate i is left out of the step-size control, else 0 (also for a NULL s). */
AP_API int ap_sim_uncontrolled(const ap_sim *s, int i);

/* ---- the global error on the outputs ---------------------------------------------------- */

/* The output channels of a run at the simulation's current state into row (nc entries);
 * AP_OK or a negative status. */
typedef int (*ap_output_fn)(ap_sim *s, double *row, void *user);
/* Called once on each simulation the functions below create (add events, set uncontrolled
 * coordinates), or NULL; AP_OK or a negative status. */
typedef int (*ap_sim_setup_fn)(ap_sim *s, void *user);

/* The reference run's settings for a run with def: the same model and initial state, method
 * dop853 (bdf when def uses bdf or adams: the model is likely stiff), mode minimal (projected
 * when def is projected), rtol = max(def->rtol / 100, 1e-14) and atol = max(def->atol / 100,
 * 1e-16) (fixed-step methods: rtol 1e-12, atol 1e-14); for bdf the rtol is not taken below
 * its floor 1e-8 (ap_method_info.rtol_floor), so the estimate of a bdf run tighter than 1e-6
 * is no longer reliable (ap_error_report.reliable). Everything else is copied. */
AP_API void ap_error_reference_def(const ap_sim_def *def, ap_sim_def *ref);
/* Fold one output row into the running per-channel maxima: err[c] = max(err[c],
 * |row[c] - ref[c]|), scale[c] = max(scale[c], |ref[c]|). Start both at 0. */
AP_API void ap_error_fold(int nc, const double *row, const double *ref, double *err,
                          double *scale);
/* The run's error: max over c of err[c] / max(1, scale[c]); 0 when nc is 0. */
AP_API double ap_error_norm(int nc, const double *err, const double *scale);

typedef struct ap_error_report {
  double error;           /* the estimated global error (ap_error_norm); units as above */
  int reliable;           /* 1 when the reference's tolerance is at least 10 x tighter */
  ap_sim_def ref;         /* the reference's settings (ap_error_reference_def) */
  ap_sim_stats run, ref_stats;   /* steps and evaluations of the run and of the reference
                                    (both reference runs when a second one was made) */
  ap_sim_stats ref_last;         /* the last reference run alone (at ref.rtol) */
} ap_error_report;

/* Run def from (t0, q0, v0) and its reference (ap_error_reference_def) through the nt output
 * times times[0 .. nt-1] (increasing, after t0), call out on each at every time, and fill
 * err (nc, may be NULL) with the largest |difference| per channel, scale (nc, may be NULL)
 * with the largest |value| per channel of the reference, and *rep. rows (nt x nc row-major,
 * may be NULL) receives the run's own outputs. AP_ERR_ARG for a NULL model, def, state, out
 * or rep, nt < 1 or nc < 0; a failure of either run returns its status with msg naming the
 * run ("run" or "reference") and the time. */
AP_API int ap_global_error(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                           const double *v0, const double *times, int nt, int nc,
                           ap_output_fn out, ap_sim_setup_fn setup, void *user, double *rows,
                           double *err, double *scale, ap_error_report *rep, char *msg,
                           size_t msg_len);

/* The reference half of ap_global_error, against rows (nt x nc, row-major) the caller's run
 * with def already produced at times: ref_rows (nt x nc, may be NULL) receives the
 * reference's rows; rep->run is left zero. An estimate below 30 x the reference's rtol cannot
 * tell the run's error from the reference's (a run whose steps were set by the output times
 * took the same steps as its reference): a second reference then runs at max(1e-14,
 * min(rtol_ref, estimate) / 100) and replaces the first (rep->ref says which ran last,
 * rep->ref_stats counts both). Arguments and failures as for ap_global_error. */
AP_API int ap_error_against(const ap_model *m, const ap_sim_def *def, double t0,
                            const double *q0, const double *v0, const double *times, int nt,
                            int nc, ap_output_fn out, ap_sim_setup_fn setup, void *user,
                            const double *rows, double *ref_rows, double *err, double *scale,
                            ap_error_report *rep, char *msg, size_t msg_len);

/* ---- accuracy on demand ------------------------------------------------------------------ */

#define AP_PICK_MAX 4   /* candidate methods the pilot tries */

typedef struct ap_pick_report {
  ap_sim_def def;          /* the choice: the caller's def with method, rtol and atol set
                              (atol = rtol) */
  double accuracy;         /* the requested global error (units as above) */
  double predicted_error;  /* the error the pilot predicts for the choice */
  double predicted_evals;  /* the evaluations it predicts for the choice */
  long pilot_evals;        /* evaluations the pilot spent, all candidates together */
  double estimated_error;  /* the chosen setting's error, estimated by ap_global_error */
  long evals;              /* the chosen setting's evaluations (its own run) */
  long verify_evals;       /* evaluations of the checks (runs and references) */
  int tries;               /* checks made (1: the pilot's prediction held) */
  int ncand;               /* candidates tried */
  struct {
    const char *method;    /* "dop853", "dopri5", "bs3" */
    double rtol;           /* pilot tolerance (its reference at rtol / 100) */
    double error;          /* estimated global error at that rtol */
    double rtol_pick;      /* the rtol predicted to reach the accuracy */
    double evals;          /* evaluations predicted there (infinite when it cannot) */
  } cand[AP_PICK_MAX];
} ap_pick_report;

/* Choose the method and tolerance that reach the global error `accuracy` (> 0, >= 1e-12) on
 * the outputs at the fewest evaluations: for each candidate (dop853; dopri5 for accuracy >= 1e-6; bs3 for >= 1e-4), a pilot
 * over the whole interval at a loose tolerance and its reference 100 x tighter gives the
 * error per unit rtol; the rtol that reaches accuracy / 3 (a safety factor for the error's
 * growth as the tolerance tightens) follows, and its cost from the pilot's evaluations and the
 * method's order. The choice is then checked by its own error estimate and tightened until
 * the estimate is below accuracy / 1.5 (at most 6 checks). def gives the mode and the other settings (its method and tolerances are
 * replaced). The same arguments as ap_global_error otherwise. AP_ERR_ARG for a NULL argument
 * or an accuracy out of range; a failed pilot drops its candidate, and AP_ERR_SOLVER when
 * every candidate failed. */
AP_API int ap_accuracy_pick(const ap_model *m, const ap_sim_def *def, double t0,
                            const double *q0, const double *v0, const double *times, int nt,
                            int nc, ap_output_fn out, ap_sim_setup_fn setup, void *user,
                            double accuracy, ap_pick_report *pick, char *msg,
                            size_t msg_len);

#ifdef __cplusplus
}
#endif
#endif
