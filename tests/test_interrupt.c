/* test_interrupt: ap_sim_set_poll, the way a caller stops a long ap_sim_advance.
 *
 * The knife edge on an inclined plane (tests/refsys.h, closed form): in each mode (minimal,
 * projected, DAE), one advance over 20 s is asked to stop at the 40th poll. It must return
 * AP_ERR_INTERRUPTED after exactly 40 polls, at a time before the end, with ap_sim_time,
 * ap_sim_q and ap_sim_v describing that accepted step (the closed form there, within the
 * tolerance the run asks for); then, the poll removed, the same simulation must reach the end
 * and match the closed form there too. A poll that never fires changes nothing: the result is
 * the same to the last bit as a run without one. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "refsys.h"

typedef struct counter {
  int calls, stop_at;
  double last_t;
} counter;

static int poll_fn(double t, void *user) {
  counter *c = user;
  c->last_t = t;
  return ++c->calls >= c->stop_at ? 7 : 0;
}

/* Largest difference of (q, v) of s from the closed form at its time. */
static double error(const rs_knife *p, const double *q0, const double *v0, const ap_sim *s) {
  double q[3], v[3], e = 0.0;
  rs_knife_exact(p, q0, v0, ap_sim_time(s), q, v, NULL);
  for (int i = 0; i < 3; i++)
    e = fmax(e, fmax(fabs(ap_sim_q(s)[i] - q[i]), fabs(ap_sim_v(s)[i] - v[i])));
  return e;
}

static void test_mode(ap_mode mode) {
  rs_knife p = {1.0, 0.5, 9.81, 0.3};
  ap_system_def def;
  double q0[3], v0[3];
  rs_knife_initial(0.0, 0.0, 0.3, 1.0, 1.5, q0, v0);
  rs_knife_system(&p, &def);
  ap_model *m = NULL;
  char msg[512];
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_OK);
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.rtol = 1e-10, sd.atol = 1e-12;
  ap_sim *s = NULL, *r = NULL;
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &r, msg, sizeof msg), AP_OK);
  if (!s || !r) return;
  counter c = {0, 40, -1.0};
  ap_sim_set_poll(s, poll_fn, &c);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 20.0), AP_ERR_INTERRUPTED);
  AP_CHECK_EQ_INT(c.calls, 40);
  AP_CHECK(ap_sim_time(s) > 0.0 && ap_sim_time(s) < 20.0 && ap_sim_time(s) == c.last_t);
  AP_CHECK(strstr(ap_sim_message(s), "interrupted at t = ") != NULL);
  AP_CHECK_LE(error(&p, q0, v0, s), 1e-6);   /* the state is that of the time reached */
  ap_sim_set_poll(s, NULL, NULL);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 20.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_time(s) == 20.0, 1);
  AP_CHECK_LE(error(&p, q0, v0, s), 1e-6);
  /* A poll that never stops the run leaves every step as it was. */
  counter never = {0, 1 << 30, -1.0};
  ap_sim_set_poll(r, poll_fn, &never);
  AP_CHECK_EQ_INT(ap_sim_advance(r, 5.0), AP_OK);
  ap_sim *plain = NULL;
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &plain, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(plain, 5.0), AP_OK);
  AP_CHECK(never.calls > 40);
  AP_CHECK_EQ_INT(memcmp(ap_sim_q(r), ap_sim_q(plain), 3 * sizeof(double)), 0);
  ap_sim_free(plain);
  ap_sim_free(r);
  ap_sim_free(s);
  ap_model_free(m);
}

int main(void) {
  test_mode(AP_MODE_MINIMAL);
  test_mode(AP_MODE_PROJECTED);
  test_mode(AP_MODE_DAE);
  AP_CHECK(strcmp(ap_strerror(AP_ERR_INTERRUPTED), "interrupted") == 0);
  return ap_check_finish("test_interrupt");
}
