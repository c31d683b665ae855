/* Body quantities (body.h, ap_body_qty): position and velocity of a body's origin, its Z-Y-X
 * (roll, pitch, yaw) and Z-X-Z (heading, tilt, spin) angles and its angular velocity, read from
 * the kinematics the position and velocity stages left in the scratch (kbody: o, vo, R, w).
 *
 * Angles from R (column-major, R[i + 3 j] = R_(i+1)(j+1)):
 *   roll = atan2(R32, R33), pitch = atan2(-R31, hypot(R11, R21)), yaw = atan2(R21, R11);
 *   tilt = atan2(hypot(R13, R23), R33), heading = atan2(R13, -R23), spin = atan2(R31, R32),
 *   and at tilt 0 (hypot(R13, R23) <= 1e-12, as lib/scene's `angles` output) heading =
 *   atan2(R21, R11), spin = 0.
 * Generic in the scalar (model/model.h; body_qty_cs.c): in the complex-step build atan2 is
 * continued by its exact first-order term, atan2(y, x) = atan2(Re y, Re x) + i (Re x Im y -
 * Re y Im x) / (Re x^2 + Re y^2), so the imaginary parts carry the exact partial derivatives
 * of every quantity; hypot is sqrt(a^2 + b^2), analytic. Decisions (the tilt-0 branch) are
 * taken on real parts. */
#include "model/model.h"
#ifndef AP_SC_COMPLEX
#include "model/tree_model.h"
#endif

static ap_sc bq_atan2(ap_sc y, ap_sc x) {
#ifdef AP_SC_COMPLEX
  double a = creal(x), b = creal(y);
  return atan2(b, a) + (a * cimag(y) - b * cimag(x)) / (a * a + b * b) * _Complex_I;
#else
  return atan2(y, x);
#endif
}

ap_sc ap_bq_value(const ap_bmodel *M, ap_sc *S, int body, int which) {
  kbody B = ap_kin_body(M, S, body);
  const ap_sc *R = B.R;
  ap_sc h = SC_HYPOT(R[6], R[7]);
  int lock = SC_MAG(h) <= 1e-12;
  switch ((ap_body_qty)which) {
    case AP_BODY_X: case AP_BODY_Y: case AP_BODY_Z: return B.o[which - AP_BODY_X];
    case AP_BODY_VX: case AP_BODY_VY: case AP_BODY_VZ: return B.vo[which - AP_BODY_VX];
    case AP_BODY_ROLL: return bq_atan2(R[5], R[8]);
    case AP_BODY_PITCH: return bq_atan2(-R[2], SC_HYPOT(R[0], R[1]));
    case AP_BODY_YAW: return bq_atan2(R[1], R[0]);
    case AP_BODY_HEADING: return lock ? bq_atan2(R[1], R[0]) : bq_atan2(R[6], -R[7]);
    case AP_BODY_TILT: return bq_atan2(h, R[8]);
    case AP_BODY_SPIN: return lock ? 0.0 : bq_atan2(R[2], R[5]);
    case AP_BODY_WX: case AP_BODY_WY: case AP_BODY_WZ: return B.w[which - AP_BODY_WX];
    case AP_BODY_QTY_COUNT: break;
  }
  return NAN;
}

#ifndef AP_SC_COMPLEX
int ap_body_quantity(const ap_model *m, const ap_data *d, int body, int which, double *value) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !value || body < 0 ||
      body >= ap_bm(m)->nb || which < 0 || which >= AP_BODY_QTY_COUNT)
    return AP_ERR_ARG;
  *value = ap_bq_value(ap_tree_layout(m), ap_bm_scratch(d), body, which);
  return AP_OK;
}
#endif
