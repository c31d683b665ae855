/* Rolling disk (docs/references.md §4) built from a body: the default demo of the body layer.
 *
 * A thin uniform disk (radius 0.3 m, mass 1.5 kg) rests on the ground plane on a plane-contact
 * joint: coordinates x, y of its centre and a unit quaternion; its height is r |sin| of the
 * axis tilt, from the disk's support function. A rolling constraint (no slip of the contact
 * point) and gravity complete it. Started leaning 0.25 rad while rolling forward and turning,
 * it wobbles round a curving path; Appell's equations in minimal mode keep the two rolling
 * rows to round-off. Uses the public API only.
 *
 * Prints the path, the lean, the energy drift and the constraint residual; exits non-zero if
 * the energy drifts by more than 1e-9 (relative) or |A v + a0| exceeds 1e-12. */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#define RTOL 1e-11

static int fail(const char *what, int st, const char *msg) {
  fprintf(stderr, "rolling_disk: %s: %s: %s\n", what, ap_strerror(st), msg);
  return 1;
}

int main(void) {
  /* 1. The model: one body, one joint, one constraint, one effect. */
  ap_builder *b = NULL;
  int st = ap_builder_create("rolling disk", &b);
  if (st != AP_OK) return fail("builder", st, "");
  ap_body_def disk = ap_body_def_default();
  disk.name = "disk";
  disk.shape.kind = AP_SHAPE_DISK;
  disk.shape.radius = 0.3;
  st = ap_body_def_uniform(&disk, 1.5);     /* I = m r^2 / 4, m r^2 / 4, m r^2 / 2 */
  ap_joint_def contact = ap_joint_def_default();
  contact.kind = AP_JOINT_PLANE_CONTACT;
  contact.child = 0;
  ap_constraint_def roll = ap_constraint_def_default();
  roll.name = "roll";
  roll.kind = AP_CON_ROLLING;
  roll.body = 0;
  ap_effect_def gravity = ap_effect_def_default();   /* (0, 0, -9.81) */
  if (st == AP_OK) st = ap_builder_add_body(b, &disk, NULL);
  if (st == AP_OK) st = ap_builder_add_joint(b, &contact, NULL);
  if (st == AP_OK) st = ap_builder_add_constraint(b, &roll, NULL);
  if (st == AP_OK) st = ap_builder_add_effect(b, &gravity, NULL);
  ap_model *m = NULL;
  if (st == AP_OK) st = ap_builder_compile(b, &m);
  if (st != AP_OK) return fail("compile", st, ap_builder_message(b));
  ap_builder_free(b);

  /* 2. Initial state: rolling along x, leaning 0.25 rad: the axis (body z) is
   *    a = (0, cos 0.25, -sin 0.25), body z turned about x by -(pi/2 + 0.25). Spin 7 rad/s
   *    about the axis, turning at 1.2 rad/s about the vertical; the centre's velocity follows
   *    from rolling (ap_body_complete_speeds keeps the angular velocity, solves the rest). */
  double q0[6] = {0.0, 0.0}, v0[5], ex[3] = {1, 0, 0}, a[3] = {0, cos(0.25), -sin(0.25)};
  ap_quat_from_axis_angle(ex, -(1.5707963267948966 + 0.25), q0 + 2);
  v0[2] = 7.0 * a[0], v0[3] = 7.0 * a[1], v0[4] = 7.0 * a[2] + 1.2;
  int given[5] = {0, 0, 1, 1, 1};
  ap_data *d = NULL;
  if ((st = ap_data_create(m, &d)) != AP_OK) return fail("data", st, "");
  if ((st = ap_body_complete_speeds(m, d, q0, given, v0)) != AP_OK)
    return fail("initial speeds", st, d->msg);
  double T0, V0;
  d->t = 0.0;
  for (int i = 0; i < 6; i++) d->q[i] = q0[i];
  for (int i = 0; i < 5; i++) d->v[i] = v0[i];
  if ((st = ap_body_energy(m, d, &T0, &V0)) != AP_OK) return fail("energy", st, d->msg);

  /* 3. Simulate 10 s in minimal mode. */
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_MINIMAL;
  sd.method = "verner6";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  ap_sim *s = NULL;
  char msg[512];
  if ((st = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg)) != AP_OK)
    return fail("simulation", st, msg);
  printf("Rolling disk r = 0.3 m, m = 1.5 kg (plane-contact joint + rolling + gravity), "
         "minimal mode, verner6, rtol %.0e\n\n", RTOL);
  printf("%5s %10s %10s %10s %12s %12s\n", "t", "x", "y", "lean", "dE/E", "|Av+a0|");
  double drift = 0.0, resid = 0.0, E0 = T0 + V0;
  for (int i = 0; i <= 10; i++) {
    if (i > 0 && (st = ap_sim_advance(s, 1.0 * i)) != AP_OK)
      return fail("advance", st, ap_sim_message(s));
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    const ap_data *sdat = ap_sim_data(s);
    double T, V, R[9];
    for (int j = 0; j < 6; j++) d->q[j] = q[j];
    for (int j = 0; j < 5; j++) d->v[j] = v[j];
    if ((st = ap_body_energy(m, d, &T, &V)) != AP_OK) return fail("energy", st, d->msg);
    ap_quat_to_matrix(q + 2, R);
    double e = fabs(T + V - E0) / E0, r = ap_constraint_residual(sdat, v);
    drift = fmax(drift, e), resid = fmax(resid, r);
    printf("%5.1f %10.6f %10.6f %10.6f %12.2e %12.2e\n", ap_sim_time(s), q[0], q[1],
           atan2(-R[8], hypot(R[6], R[7])), e, r);
  }
  ap_sim_stats stats;
  ap_sim_get_stats(s, &stats);
  printf("\nenergy drift %.2e (relative), constraint residual %.2e, %ld steps, %ld evaluations\n",
         drift, resid, stats.steps, stats.rhs_evals);
  ap_sim_free(s);
  ap_data_free(d);
  ap_model_free(m);
  return drift <= 1e-9 && resid <= 1e-12 ? 0 : 1;
}
