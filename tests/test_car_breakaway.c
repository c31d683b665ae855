/* The Ackermann car cornering faster and faster until a wheel breaks away (docs/vehicles.md
 * "Breaking away in a turn"): examples/scenes/car_breakaway.yaml, the suspended car on a free
 * chassis with a sideways-sprung hub and a vertically sprung strut per wheel (unique loads and
 * sideways forces), steered at the fixed Ackermann angles of steer 0.3 rad and sped up by a
 * drive torque of 1 N m per rear wheel from 2 m/s.
 *
 *  (1) Slip onset: on the run without friction (the scene's mu set to 1e9: the contacts never
 *      leave their rolling mode, the same model as without friction) an event on
 *      max_i(friction_ratio_i) - mu (rising, reactions stage, located to 1e-11 relative) finds
 *      t* and the wheel whose ratio gets there first; the run with mu = 0.5 must record that
 *      wheel's slip event at t* (1e-9 relative) and have it sliding after.
 *  (2) The loads in the quasi-steady turn against a closed form (qs_turn below): the car as
 *      rigid at its design height turning about the fixed centre C = (0, R) of the Ackermann
 *      steer with the yaw rate of the energy balance, Omega = Omega0 + Omega' t,
 *      J_C Omega' = 2 T R / r (J_C: every body's m |p - C|^2 + I_zz plus the wheels' spin
 *      inertia I_a (d_i / r)^2). Every body's acceleration follows; the wheels' forward forces
 *      from their spin (T - I_a w') / r; the sideways forces from the whole car's force
 *      balance with the hub springs (F_i = m_o a_i . e_i + k_y u . e_i, one chassis shift u,
 *      e_i each wheel's axle); the loads from sum N = M g and the roll and pitch moments about
 *      the ground point below the rear axle (m z a and the wheels' gyroscopic moments
 *      I_a w (Omega x e_i) and I_a w' e_i), the roll moment shared between the axles as their
 *      spring rates k_f : k_r (the struts' deflections follow the chassis' heave, roll and
 *      pitch: the warp N_fl - N_fr - N_rl + N_rr weighs as k). The closed form neglects the
 *      chassis' shift u on the hubs (g M_s |u| / track per wheel at most) and the dampers' lag
 *      behind the rising loads ((c / k) |dN/dt|, which the speed's rise rate sets): their sum
 *      bounds the difference from the run without friction at t = 3 s (the transient of the
 *      start, exp(-25 t), long gone; the limit at 3.63 s).
 *  (3) Which axle breaks away: the closed form's first wheel to reach mu is the inner front
 *      (front springs kf = 40 kN/m, twice the rear: the front axle takes two thirds of the
 *      roll moment, unloads its inner wheel most, and the understeering car's front axle
 *      slides: the outer front slips next, with the rear wheels rolling, and the path widens);
 *      with soft front springs (kf = 5 kN/m) the rear takes four fifths, the inner rear goes
 *      first and the rear axle breaks away (oversteer). The run with friction must agree:
 *      first event that wheel's, the second the other wheel of its axle, the other axle
 *      rolling (minimal mode; the slides crawl at small steps where the slip direction turns).
 * Minimal and projected mode, dop853 at rtol 1e-10, atol 1e-12; DAE mode (IDA at the same
 * tolerances) for (1), within 1e3 rtol per second of motion: the friction ratio is made of
 * IDA's multipliers, less accurate than its states (5e-8 relative from minimal mode's t*). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define RTOL 1e-10
#define MU 0.5
#define NW 4
#define G 9.81

/* The scene's numbers (examples/scenes/car_breakaway.yaml). */
#define L_WB 1.2
#define TRACK 0.8
#define RW 0.15
#define STEER 0.3
#define V0 2.0
#define TORQUE 1.0
#define KY 20000.0
#define KR 20000.0
#define CZ 1000.0
#define M_O 1.7       /* hub + strut + wheel: moves sideways with the wheel */
#define M_S 20.6      /* chassis + knuckles: shift sideways on the hubs */

static const char *const WHEELS[NW] = {"roll_rl", "roll_rr", "roll_fl", "roll_fr"};

typedef struct tyres {
  const ap_model *m;
  int c[NW];     /* constraint index of each wheel's contact */
  double mu;
  int first;     /* the wheel with the largest ratio at the last evaluation */
} tyres;

static void find_tyres(runner *r, tyres *ty) {
  ty->m = ap_scene_model(r->sc);
  for (int w = 0; w < NW; w++) {
    ty->c[w] = -1;
    for (int i = 0; i < ap_scene_count(r->sc, AP_SCENE_CONSTRAINTS); i++)
      if (strcmp(ap_scene_element_name(r->sc, AP_SCENE_CONSTRAINTS, i), WHEELS[w]) == 0)
        ty->c[w] = i;
    AP_CHECK(ty->c[w] >= 0);
  }
}

static int max_ratio_minus_mu(double t, const double *q, const double *v, const ap_data *d,
                              void *user, double *out) {
  tyres *ty = user;
  double r = -INFINITY;
  (void)t, (void)q, (void)v;
  for (int w = 0; w < NW; w++) {
    ap_contact_force f;
    if (ap_body_contact_force(ty->m, d, d->lambda, ty->c[w], &f) != AP_OK) return -1;
    if (f.friction_ratio > r) r = f.friction_ratio, ty->first = w;
  }
  *out = r - ty->mu;
  return 0;
}

/* The scene in `mode` with friction coefficient mu (1e9: never slips), front springs kf. */
static int start_kf(runner *r, const char *mode, double mu, double kf) {
  char sm[64], smu[64], skf[64];
  snprintf(sm, sizeof sm, "simulation.mode=%s", mode);
  snprintf(smu, sizeof smu, "parameters.mu=%.17g", mu);
  snprintf(skf, sizeof skf, "parameters.kf=%.17g", kf);
  const char *sets[] = {sm, smu, skf};
  return runner_start(r, "car_breakaway.yaml", sets, 3, RTOL);
}

static int start(runner *r, const char *mode, double mu) {
  return start_kf(r, mode, mu, 40000.0);
}

/* ---- the quasi-static turn ---- */

typedef struct qs_body {
  double m, x, y, z, izz;
} qs_body;

typedef struct qs_out {
  double N[NW], lat[NW], lon[NW], ratio[NW], omega, u[2];
} qs_out;

static const double WX[NW] = {0, 0, L_WB, L_WB}, WY[NW] = {TRACK / 2, -TRACK / 2, TRACK / 2,
                                                           -TRACK / 2};

/* Every body at its design position (car axes: x forward from the rear axle, z up from the
 * ground), the wheels last (4 x hub 0.2, strut 0.5, wheel 1 kg). */
static int qs_bodies(qs_body *b) {
  int n = 0;
  b[n++] = (qs_body){20.0, 0.5, 0.0, 0.25, 4.0};
  b[n++] = (qs_body){0.3, L_WB, TRACK / 2, RW, 1e-3};
  b[n++] = (qs_body){0.3, L_WB, -TRACK / 2, RW, 1e-3};
  for (int w = 0; w < NW; w++) {
    b[n++] = (qs_body){0.2, WX[w], WY[w], RW, 1e-3};
    b[n++] = (qs_body){0.5, WX[w], WY[w], RW, 1e-3};
    b[n++] = (qs_body){1.0, WX[w], WY[w], RW, RW * RW / 4};
  }
  return n;
}

static void qs_acc(double x, double y, double R, double om, double omd, double *a) {
  a[0] = -om * om * x - omd * (y - R);
  a[1] = -om * om * (y - R) + omd * x;
}

/* The closed form at time t with front springs kf (header, (2)). */
static qs_out qs_turn_at(double t, double kf, double om_given) {
  qs_body b[3 + 3 * NW];
  qs_out o;
  int nb = qs_bodies(b);
  double R = L_WB / tan(STEER), Ia = RW * RW / 2, d[NW], e[NW][2], f[NW][2], J = 0, M = 0;
  for (int w = 0; w < NW; w++) {
    double del = w < 2 ? 0.0 : atan(L_WB / (R - WY[w]));
    e[w][0] = -sin(del), e[w][1] = cos(del), f[w][0] = cos(del), f[w][1] = sin(del);
    d[w] = hypot(WX[w], WY[w] - R);
    J += Ia * d[w] * d[w] / (RW * RW);
  }
  for (int i = 0; i < nb; i++)
    J += b[i].m * (b[i].x * b[i].x + (b[i].y - R) * (b[i].y - R)) + b[i].izz, M += b[i].m;
  double omd = 2 * TORQUE * R / (RW * J), om = V0 * tan(STEER) / L_WB + omd * t, a[2];
  if (isfinite(om_given)) om = om_given;
  double F[2] = {0, 0}, Mx = 0, My = 0, Sxm = 0;
  for (int i = 0; i < nb; i++) {
    qs_acc(b[i].x, b[i].y, R, om, omd, a);
    F[0] += b[i].m * a[0], F[1] += b[i].m * a[1];
    Mx -= b[i].m * b[i].z * a[1], My -= b[i].m * b[i].z * a[0], Sxm += b[i].m * b[i].x;
  }
  double K[3] = {0, 0, 0};
  for (int w = 0; w < NW; w++) {   /* forward forces, the hubs' own sideways inertia, gyro */
    o.lon[w] = ((w < 2 ? TORQUE : 0.0) - Ia * omd * d[w] / RW) / RW;
    qs_acc(WX[w], WY[w], R, om, omd, a);
    double own = M_O * (a[0] * e[w][0] + a[1] * e[w][1]);
    o.lat[w] = own;
    for (int i = 0; i < 2; i++) F[i] -= o.lon[w] * f[w][i] + own * e[w][i];
    K[0] += KY * e[w][0] * e[w][0], K[1] += KY * e[w][0] * e[w][1], K[2] += KY * e[w][1] * e[w][1];
    double s = Ia * d[w] / RW;   /* spin angular momentum per Omega: H = s Omega e */
    Mx += s * omd * e[w][0] - s * om * om * f[w][0];
    My -= s * omd * e[w][1] - s * om * om * f[w][1];
  }
  double det = K[0] * K[2] - K[1] * K[1];
  o.u[0] = (K[2] * F[0] - K[1] * F[1]) / det, o.u[1] = (K[0] * F[1] - K[1] * F[0]) / det;
  double front = (G * Sxm + My) / L_WB, rear = M * G - front;
  double Df = Mx / (TRACK / 2) * kf / (kf + KR), Dr = Mx / (TRACK / 2) * KR / (kf + KR);
  o.N[0] = (rear + Dr) / 2, o.N[1] = (rear - Dr) / 2;
  o.N[2] = (front + Df) / 2, o.N[3] = (front - Df) / 2;
  for (int w = 0; w < NW; w++) {
    o.lat[w] += KY * (o.u[0] * e[w][0] + o.u[1] * e[w][1]);
    o.ratio[w] = hypot(o.lat[w], o.lon[w]) / o.N[w];
  }
  o.omega = om;
  return o;
}

static qs_out qs_turn(double t, double kf) {
  return qs_turn_at(t, kf, NAN);
}

/* The bound on the closed form's load of wheel w at t (header, (2)). */
static double qs_bound(double t, double kf, int w) {
  const double h = 1e-3;
  qs_out o = qs_turn(t, kf), op = qs_turn(t + h, kf), om = qs_turn(t - h, kf);
  double k = w < 2 ? KR : kf, dN = (op.N[w] - om.N[w]) / (2 * h);
  return CZ / k * fabs(dN) + G * M_S * hypot(o.u[0], o.u[1]) / TRACK;
}

/* The closed form's first wheel to reach mu and when (bisection on max ratio - mu). */
static double qs_crossing(double kf, double mu, int *first) {
  double a = 0.0, b = 6.0;
  for (int it = 0; it < 60; it++) {
    double c = 0.5 * (a + b), r = 0;
    qs_out o = qs_turn(c, kf);
    for (int w = 0; w < NW; w++) r = fmax(r, o.ratio[w]);
    if (r >= mu) b = c; else a = c;
  }
  qs_out o = qs_turn(b, kf);
  *first = 0;
  for (int w = 1; w < NW; w++)
    if (o.ratio[w] > o.ratio[*first]) *first = w;
  return b;
}

/* t* and the first wheel on the run without friction. */
static double crossing(const char *mode, int *first) {
  runner r;
  double t = NAN;
  *first = -1;
  AP_CHECK_EQ_INT(start(&r, mode, 1e9), AP_OK);
  if (r.sim) {
    tyres ty;
    find_tyres(&r, &ty);
    ty.mu = MU, ty.first = -1;
    ap_event_def def = ap_event_def_default();
    def.name = "ratio", def.fn = max_ratio_minus_mu, def.user = &ty;
    def.direction = AP_EVENT_RISING, def.action = AP_EVENT_STOP, def.stage = AP_EVENT_REACTIONS;
    AP_CHECK_EQ_INT(ap_sim_add_event(r.sim, &def), AP_OK);
    if (ap_sim_advance(r.sim, 6.0) == AP_STOPPED) t = ap_sim_time(r.sim), *first = ty.first;
  }
  runner_stop(&r);
  return t;
}

/* The slip event of the run with friction against t* of the run without (bound: tol * t*);
 * ref (finite): t* of another mode, which the event must also meet. Returns t*. */
static double test_onset(const char *mode, double tol, double ref) {
  int first;
  double ts = crossing(mode, &first);
  runner r;
  AP_CHECK(isfinite(ts) && first >= 0);
  AP_CHECK_EQ_INT(start(&r, mode, MU), AP_OK);
  if (r.sim && isfinite(ts) && first >= 0) {
    tyres ty;
    find_tyres(&r, &ty);
    AP_CHECK_EQ_INT(ap_sim_advance(r.sim, ts + 1e-8), AP_OK);
    ap_event_record rec;
    int n = runner_event(r.sim, 0, &rec);
    char want[64];
    snprintf(want, sizeof want, "%s.slip", WHEELS[first]);
    int sliding = ap_sim_contact_mode(r.sim, ty.c[first]) == AP_CONTACT_SLIDING;
    printf("  %s: without friction the %s ratio reaches mu = %g first, at t* = %.15g; with "
           "friction first event %s at %.15g (|t - t*| / t* = %.2g", mode, WHEELS[first], MU,
           ts, rec.name, rec.t, fabs(rec.t - ts) / ts);
    if (isfinite(ref)) printf("; from minimal mode's t* %.2g", fabs(rec.t - ref) / ref);
    printf(", bound %.2g), sliding after: %d\n", tol, sliding);
    AP_CHECK(n >= 1 && strcmp(rec.name, want) == 0 && sliding);
    AP_CHECK_LE(fabs(rec.t - ts), tol * ts);
    if (isfinite(ref)) AP_CHECK_LE(fabs(rec.t - ref), tol * ref);
  }
  runner_stop(&r);
  return ts;
}

static double yaw_of(const double *quat) {
  return atan2(2 * (quat[0] * quat[3] + quat[1] * quat[2]),
               1 - 2 * (quat[2] * quat[2] + quat[3] * quat[3]));
}

/* (2): the run without friction at t = 3 s against the closed form. */
static void test_loads(void) {
  const double tq = 3.0, kf = 40000.0, h = 1e-3;
  runner r;
  AP_CHECK_EQ_INT(start(&r, "minimal", 1e9), AP_OK);
  if (!r.sim) return runner_stop(&r);
  tyres ty;
  find_tyres(&r, &ty);
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, tq), AP_OK);
  const double *lam = NULL;
  AP_CHECK_EQ_INT(ap_sim_reactions(r.sim, &lam), AP_OK);
  qs_out o = qs_turn(tq, kf), op = qs_turn(tq + h, kf), om = qs_turn(tq - h, kf);
  double psi = yaw_of(ap_sim_q(r.sim) + 3), c = cos(psi), s = sin(psi);
  double sumN = 0, Fcar[2] = {0, 0}, Fqs[2] = {0, 0}, worst = 0, u = hypot(o.u[0], o.u[1]);
  for (int w = 0; w < NW; w++) {
    ap_contact_force f;
    AP_CHECK_EQ_INT(ap_body_contact_force(ty.m, ap_sim_data(r.sim), lam, ty.c[w], &f), AP_OK);
    double k = w < 2 ? KR : kf, dN = (op.N[w] - om.N[w]) / (2 * h);
    double bound = qs_bound(tq, kf, w);
    sumN += f.normal;
    Fcar[0] += c * f.force[0] + s * f.force[1], Fcar[1] += -s * f.force[0] + c * f.force[1];
    printf("    %s: load %.6g N, closed form %.6g N (difference %.3g, bound %.3g: damper lag "
           "%.3g, shift %.3g); friction ratio %.5g, closed form %.5g\n", WHEELS[w], f.normal,
           o.N[w], f.normal - o.N[w], bound, CZ / k * fabs(dN), G * M_S * u / TRACK,
           f.friction_ratio, o.ratio[w]);
    AP_CHECK_LE(fabs(f.normal - o.N[w]), bound);
    worst = fmax(worst, fabs(f.normal - o.N[w]) / bound);
  }
  double wz = ap_sim_v(r.sim)[5];
  qs_out ow = qs_turn_at(tq, kf, wz);
  for (int w = 0; w < NW; w++) {
    double R = L_WB / tan(STEER), del = w < 2 ? 0.0 : atan(L_WB / (R - WY[w]));
    Fqs[0] += ow.lon[w] * cos(del) - ow.lat[w] * sin(del);
    Fqs[1] += ow.lon[w] * sin(del) + ow.lat[w] * cos(del);
  }
  /* sum N - M g = the vertical accelerations (the struts following the loads: |N''| / k);
   * the ground's horizontal force = the bodies' m a at the run's yaw rate, but for the
   * chassis' shift u on the hubs (M_S Omega^2 |u|) */
  double Ndd = 0;
  for (int w = 0; w < NW; w++)
    Ndd = fmax(Ndd, fabs(op.N[w] - 2 * o.N[w] + om.N[w]) / (h * h) / (w < 2 ? KR : kf));
  double bz = 27.4 * Ndd, bh = M_S * wz * wz * u;
  printf("  loads at t = %g s (yaw rate %.9g rad/s, closed form %.9g): sum %.12g N against M g "
         "%.12g (bound %.2g); ground force in car axes (%.6g, %.6g) N, closed form at the run's "
         "yaw rate (%.6g, %.6g) (bound %.2g); the largest load difference is %.2f of its "
         "bound\n", tq, wz, o.omega, sumN, 27.4 * G, bz, Fcar[0], Fcar[1], Fqs[0], Fqs[1], bh,
         worst);
  AP_CHECK_LE(fabs(sumN - 27.4 * G), bz);
  AP_CHECK_LE(hypot(Fcar[0] - Fqs[0], Fcar[1] - Fqs[1]), bh);
  runner_stop(&r);
}

/* (3): which axle breaks away, with front springs kf; the closed form names the first wheel. */
static void test_axle(double kf, double t_end) {
  int first, partner;
  double tq = qs_crossing(kf, MU, &first);
  partner = first ^ 1;   /* the other wheel of its axle (rl/rr, fl/fr) */
  runner r;
  AP_CHECK_EQ_INT(start_kf(&r, "minimal", MU, kf), AP_OK);
  if (!r.sim) return runner_stop(&r);
  tyres ty;
  find_tyres(&r, &ty);
  int rc = ap_sim_advance(r.sim, t_end);
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_event_record e0, e1;
  int n = runner_event(r.sim, 0, &e0);
  runner_event(r.sim, 1, &e1);
  char w0[64], w1[64];
  snprintf(w0, sizeof w0, "%s.slip", WHEELS[first]);
  snprintf(w1, sizeof w1, "%s.slip", WHEELS[partner]);
  int other_rolling = 1, axle_sliding = 1;
  for (int w = 0; w < NW; w++) {
    int mode = ap_sim_contact_mode(r.sim, ty.c[w]);
    if (w == first || w == partner) axle_sliding &= mode == AP_CONTACT_SLIDING;
    else other_rolling &= mode == AP_CONTACT_ROLLING;
  }
  double wz = ap_sim_v(r.sim)[5], v = hypot(ap_sim_v(r.sim)[0], ap_sim_v(r.sim)[1]);
  printf("  kf = %g N/m: the closed form's %s reaches mu first at %.4f s; the run: %s at %.6f s, "
         "%s at %.6f s (%d events by %g s); at %g s the %s axle slides (%d), the other rolls "
         "(%d); path radius v / yaw rate %.4f m (%.4f m while the tyres hold)\n", kf,
         WHEELS[first], tq, e0.name, e0.t, e1.name, e1.t, n,
         t_end, t_end, first < 2 ? "rear" : "front", axle_sliding, other_rolling, v / wz,
         L_WB / tan(STEER));
  AP_CHECK(n >= 2 && strcmp(e0.name, w0) == 0 && strcmp(e1.name, w1) == 0);
  AP_CHECK(axle_sliding && other_rolling);
  /* the front axle sliding, the car runs wide (understeer); the rear, it turns in (oversteer) */
  AP_CHECK(first < 2 ? v / wz < L_WB / tan(STEER) : v / wz > L_WB / tan(STEER));
  /* the closed form's crossing is off by its ratio's error (the load bound) over the ratio's
   * rate */
  qs_out o = qs_turn(tq, kf), o1 = qs_turn(tq + 1e-3, kf);
  double rate = (o1.ratio[first] - o.ratio[first]) / 1e-3;
  double bt = MU * qs_bound(tq, kf, first) / o.N[first] / rate;
  double R = L_WB / tan(STEER), v_qs = o.omega * R, v_run = e0.v ? e0.v[5] * R : NAN;
  printf("    first slip %.4f s from the closed form's crossing (bound %.3f s): at %.4f m/s, "
         "the closed form's %.4f m/s (the rear-axle midpoint's speed)\n", fabs(e0.t - tq), bt,
         v_run, v_qs);
  AP_CHECK_LE(fabs(e0.t - tq), bt);
  runner_stop(&r);
}

int main(void) {
  printf("the car cornering faster and faster:\n");
  test_loads();
  double ts = test_onset("minimal", 1e-9, NAN);
  test_onset("projected", 1e-9, ts);
  /* DAE (IDA): its multipliers, which the friction ratio is made of, carry IDA's error; the
   * bound is the DAE cross-checks' 1e3 rtol per second of motion (tests/test_vehicles_cvode.c) */
  test_onset("dae", 1e3 * RTOL * ts, ts);
  test_axle(40000.0, 4.3);
  test_axle(5000.0, 4.6);
  return ap_check_finish("test_car_breakaway");
}
