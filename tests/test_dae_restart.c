/* A restart of IDA mid-run allocates nothing (issue 23, item 11: allocations of a run at its
 * creation). An input that changes at t = 1 s restarts the DAE mode's integrator there
 * (ap_dae_restart: the multipliers by least squares, whose LAPACK workspace and residual
 * vector were made at creation). The advance through the restart makes no heap allocation,
 * so one that is made to fail changes nothing; the trajectory agrees with minimal mode's
 * under the same input within the DAE cross-check's bound, 10 (rtol |x|max + atol) with
 * |x|max the largest |q_i| at t = 2 (tests/test_dae.c). The model: the Chaplygin sleigh of docs/references.md §2 with a force
 * on its first speed. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "alloc.h"
#include "appell/appell.h"
#include "check.h"
#include "refsys.h"

static const double RTOL = 1e-9, ATOL = 1e-11;

/* Runs the sleigh in mode to t = 2 with the input at 0, then 0.5 from t = 1; q out. The
 * advance through the restart is counted (allocations), with one made to fail when inject. */
static void run(ap_model *m, ap_mode mode, int inject, double q[3], long *allocs,
                long *restarts) {
  double q0[3], v0[3];
  rs_sleigh_initial(0, 0, RS_PI, 0.1, 0.2, q0, v0);
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.rtol = RTOL, sd.atol = ATOL;
  ap_sim *sim = NULL;
  char msg[512] = "";
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &sim, msg, sizeof msg), AP_OK);
  if (!sim) return;
  const char *in[] = {ap_model_speed_name(m, 0), NULL};
  AP_CHECK_EQ_INT(ap_sim_declare_inputs(sim, in), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(sim, 1.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_set_input(sim, in[0], 0.5), AP_OK);
  ap_sim_stats st;
  ap_sim_get_stats(sim, &st);
  long before = n_alloc, restarts0 = st.restarts;
  ap_alloc_failed = 0;
  if (inject) ap_alloc_fail_at(0);
  int rc = ap_sim_advance(sim, 2.0);
  ap_alloc_fail_at(-1);
  *allocs = n_alloc - before;
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) printf("%s\n", ap_sim_message(sim));
  AP_CHECK_EQ_INT(ap_alloc_failed, 0);
  ap_sim_get_stats(sim, &st);
  *restarts = st.restarts - restarts0;
  memcpy(q, ap_sim_q(sim), sizeof(double) * 3);
  ap_sim_free(sim);
}

int main(void) {
  if (!AP_COUNT_ALLOC) {
    printf("allocation count skipped under AddressSanitizer\n");
    return 0;
  }
  rs_sleigh sp = {1.0, 1.0, 1.0};
  ap_system_def def;
  rs_sleigh_system(&sp, 0, &def);
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, NULL, 0), AP_OK);
  double qd[3] = {0}, qi[3] = {0}, qm[3] = {0};
  long allocs = -1, restarts = 0, allocs_m = -1, restarts_m = 0;
  run(m, AP_MODE_DAE, 0, qd, &allocs, &restarts);
  printf("DAE mode, t = 1 .. 2 with the input's restart: %ld allocations, %ld restarts\n",
         allocs, restarts);
  AP_CHECK_EQ_INT(allocs, 0);
  AP_CHECK(restarts >= 1);
  run(m, AP_MODE_DAE, 1, qi, &allocs, &restarts);   /* a failing allocation is never asked */
  run(m, AP_MODE_MINIMAL, 0, qm, &allocs_m, &restarts_m);
  double xmax = 0.0;
  for (int i = 0; i < 3; i++) xmax = fmax(xmax, fabs(qm[i]));
  for (int i = 0; i < 3; i++) {
    printf("q[%d]: DAE %.12f, minimal %.12f\n", i, qd[i], qm[i]);
    AP_CHECK_NEAR(qd[i], qm[i], 10 * (RTOL * xmax + ATOL));
    AP_CHECK_NEAR(qi[i], qd[i], 0.0);
  }
  ap_model_free(m);
  return ap_check_finish("dae_restart");
}
