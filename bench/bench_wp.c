/* bench_wp: work-precision sweep of Appell on the reference problems with exact answers
 * (docs/references.md: knife edge, Chaplygin sleigh, ball on a turntable at constant and at
 * time-varying Omega, particle on a rotating line in its 3-D form with rheonomic rows) and on
 * the rolling disk (a body-layer model: disk on a plane-contact joint, rolling, gravity), side
 * by side with "the limit": each problem's hand-reduced closed-form ODE integrated by exactly
 * the same SUNDIALS stepper (lib/integrate/stepper.h), measured in the same run.
 *
 * The disk has no closed form: its reference positions come from its hand-reduced ODE at
 * rtol = atol = 1e-14 (fehlberg8), and Appell's minimal and DAE modes at tight tolerances are
 * checked against them (the difference is printed: it bounds how far the reference can be
 * trusted).
 *
 * For every problem, every Appell mode (minimal, projected, DAE) and every stepper (bs3,
 * dopri5, verner6, fehlberg8, dop853, adams, bdf at rtol = atol = 1e-3 ... 1e-12; rk4 over fixed steps
 * T / (10 m), m = 2, 4, ..., 4096) one run integrates from t = 0 to T, stopping exactly at
 * NOUT = 10 equally spaced output times, and records
 *   err    the largest position error (m) over the outputs against the exact solution
 *          (max-norm of the contact point / centre / bead position),
 *   cpu    CPU time (CLOCK_PROCESS_CPUTIME_ID) of create + integrate + free, median over
 *          repeats (runs under 50 ms are repeated after an untimed warm-up),
 *   steps, rhs evaluations, error-test failures, and the largest |A v + a0| at step ends.
 * A curve stops going tighter once one run costs more than --budget seconds (default 0.4),
 * reaches 1e-13, or fails three times in a row; a run fails after 20000 steps between
 * outputs.
 *
 * Writes one CSV row per run (--csv) and the problem descriptions with the exact positions at
 * the output times (--describe), which the peers (bench/peers/) read so that every tool
 * integrates the same problem from the same state and is scored against the same numbers.
 * Ratios at equal achieved error are computed from the CSV by bench/plot/report.py.
 *
 * Usage: bench_wp [--csv FILE] [--describe FILE] [--problems a,b] [--budget S] [--quick]
 *        bench_wp --one PROBLEM TOOL MODE METHOD TOL_OR_H [--reps N]   (for callgrind)
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "integrate/stepper.h"
#include "refsys.h"

#define NOUT 10        /* output times t_i = i T / NOUT, i = 1 .. NOUT */
#define MAXS 16        /* largest state of any problem */
#define NPROB 6
/* Steps allowed between two output times: a run that needs more fails (and stops its curve)
 * instead of running for minutes (e.g. CVODE restarted after every step). */
#define WP_MAX_STEPS 20000

/* ---- problems ---------------------------------------------------------------------------- */

typedef struct wp_problem wp_problem;
struct wp_problem {
  const char *name, *title;
  ap_system_def def;        /* the Appell math-level system (refsys) */
  ap_model *body_model;     /* or a compiled body model (rolling disk) */
  int n, k;                 /* its sizes */
  double q0[MAXS], v0[MAXS];
  double T;                 /* end time (s) */
  int npos;                 /* position components compared (2 or 3) */
  void (*pos_q)(const wp_problem *pr, double t, const double *q, double *pos);
  int hn;                   /* hand-reduced ODE: size, initial state, right-hand side */
  double hy0[MAXS];
  ap_rhs_fn hand;
  void (*pos_hand)(const wp_problem *pr, double t, const double *y, double *pos);
  union {
    rs_knife knife;
    rs_sleigh sleigh;
    rs_turntable turn;
    rs_line line;
    struct { double m, r, grav; } disk;
  } p;                      /* parameters; the system's user pointer points here */
  double euler[7];          /* rolling disk: x, y, psi, theta, w1, w2, w3 at t = 0 */
  double r0, rd0;           /* rotating line: initial r, r' */
  double epos[NOUT][3];     /* exact positions at the output times */
};

/* Position = the first npos coordinates (knife, sleigh, turntable: x, y; line: X, Y, Z). */
static void pos_first(const wp_problem *pr, double t, const double *q, double *pos) {
  (void)t;
  for (int i = 0; i < pr->npos; i++) pos[i] = q[i];
}

/* Knife edge by hand: y = (x, y, phi, u, w); u' = G cos phi, w' = 0 (docs/references.md §1). */
static int knife_hand(double t, const double *y, double *yd, void *user) {
  const wp_problem *pr = user;
  double G = pr->p.knife.grav * sin(pr->p.knife.alpha), c = cos(y[2]), s = sin(y[2]);
  (void)t;
  yd[0] = y[3] * c, yd[1] = y[3] * s, yd[2] = y[4], yd[3] = G * c, yd[4] = 0.0;
  return 0;
}

/* Sleigh by hand: y = (x, y, theta, u, w); u' = a w^2, J w' = -m a u w (docs/references.md §2). */
static int sleigh_hand(double t, const double *y, double *yd, void *user) {
  const rs_sleigh *p = &((const wp_problem *)user)->p.sleigh;
  double J = p->I + p->m * p->a * p->a;
  (void)t;
  yd[0] = y[3] * cos(y[2]), yd[1] = y[3] * sin(y[2]), yd[2] = y[4];
  yd[3] = p->a * y[4] * y[4], yd[4] = -p->m * p->a * y[3] * y[4] / J;
  return 0;
}

/* Turntable by hand: y = (x, y, x', y'); x'' = -kt (Omega y)', y'' = kt (Omega x)'. */
static int turn_hand(double t, const double *y, double *yd, void *user) {
  const rs_turntable *p = &((const wp_problem *)user)->p.turn;
  double kt = p->kI / (1.0 + p->kI), W = p->Omega0 + p->dOmega * t, Wd = p->dOmega;
  yd[0] = y[2], yd[1] = y[3];
  yd[2] = -kt * (Wd * y[1] + W * y[3]);
  yd[3] = kt * (Wd * y[0] + W * y[2]);
  return 0;
}

/* Rotating line by hand: y = (r, r'); r'' = s^2 r - g cos(alpha), s = w sin(alpha). */
static int line_hand(double t, const double *y, double *yd, void *user) {
  const rs_line *p = &((const wp_problem *)user)->p.line;
  double s = p->w * sin(p->alpha);
  (void)t;
  yd[0] = y[1];
  yd[1] = s * s * y[0] - p->grav * cos(p->alpha);
  return 0;
}

/* Rolling disk by hand (docs/references.md §4, derived anew in these frames). Heading frame:
 * y1 = (cos psi, sin psi, 0), y2 = e_z x y1; lean frame: l1 = y1, l2 = cos(theta) y2 +
 * sin(theta) e_z (the disk axis; theta = tilt from upright), l3 = l1 x l2 (towards the centre
 * from the contact point, C - P = r l3). Disk angular velocity w = w1 l1 + w2 l2 + w3 l3 with
 * w1 = theta', w3 = psi' cos(theta); rolling gives v_C = r (w2 l1 - w1 l2). Newton-Euler
 * about the centre with A = m r^2/4, C = m r^2/2 (the reference's w_n = -w2, w_a = w3):
 *   (A + m r^2) w1' = (C + m r^2) w2 w3 - A w3^2 tan(theta) + m g r sin(theta)
 *   (C + m r^2) w2' = -m r^2 w1 w3,      A w3' = A w1 w3 tan(theta) - C w1 w2.
 * y = (x, y, psi, theta, w1, w2, w3); (x, y) the centre. */
static int disk_hand(double t, const double *y, double *yd, void *user) {
  const wp_problem *pr = user;
  double m = pr->p.disk.m, r = pr->p.disk.r, g = pr->p.disk.grav;
  double A = 0.25 * m * r * r, C = 0.5 * m * r * r, mr2 = m * r * r;
  double cp = cos(y[2]), sp = sin(y[2]), ct = cos(y[3]), st = sin(y[3]), tt = st / ct;
  double w1 = y[4], w2 = y[5], w3 = y[6];
  (void)t;
  yd[0] = r * (w2 * cp + w1 * ct * sp);
  yd[1] = r * (w2 * sp - w1 * ct * cp);
  yd[2] = w3 / ct;
  yd[3] = w1;
  yd[4] = ((C + mr2) * w2 * w3 - A * w3 * w3 * tt + m * g * r * st) / (A + mr2);
  yd[5] = -mr2 * w1 * w3 / (C + mr2);
  yd[6] = w1 * w3 * tt - (C / A) * w1 * w2;
  return 0;
}

static void line_pos_hand(const wp_problem *pr, double t, const double *y, double *pos) {
  rs_line_lift(&pr->p.line, t, y[0], y[1], pos, NULL);
}

/* Exact positions at the output times. */
static void fill_exact(wp_problem *pr, int which) {
  for (int i = 0; i < NOUT; i++) {
    double t = pr->T * (i + 1) / NOUT, q[MAXS], r;
    switch (which) {
      case 0: rs_knife_exact(&pr->p.knife, pr->q0, pr->v0, t, q, NULL, NULL); break;
      case 1: rs_sleigh_exact(&pr->p.sleigh, pr->q0, pr->v0, t, q, NULL); break;
      case 2:
      case 3: rs_turntable_exact(&pr->p.turn, pr->q0, pr->v0, t, q, NULL); break;
      default:
        rs_line_exact(&pr->p.line, pr->r0, pr->rd0, t, &r, NULL);
        rs_line_lift(&pr->p.line, t, r, 0.0, q, NULL);
        break;
    }
    for (int c = 0; c < pr->npos; c++) pr->epos[i][c] = q[c];
  }
}

/* The rolling disk as a body model: a uniform thin disk (body z = its axis) on a plane-contact
 * joint, the rolling constraint (2 rows) and gravity; q = (x, y, quaternion), v = (vx, vy, w).
 * The initial state comes from pr->euler: body axes (l1, -l3, l2) at spin 0, w in world axes,
 * (vx, vy) completed from the constraint. */
static void disk_setup(wp_problem *pr) {
  ap_builder *b = NULL;
  ap_body_def bd = ap_body_def_default();
  bd.name = "disk", bd.shape.kind = AP_SHAPE_DISK, bd.shape.radius = pr->p.disk.r;
  ap_joint_def jd = ap_joint_def_default();
  jd.kind = AP_JOINT_PLANE_CONTACT, jd.child = 0;
  ap_constraint_def cd = ap_constraint_def_default();
  cd.name = "roll", cd.kind = AP_CON_ROLLING, cd.body = 0;
  ap_effect_def ed = ap_effect_def_default();
  ed.gravity[2] = -pr->p.disk.grav;
  ap_data *d = NULL;
  if (ap_body_def_uniform(&bd, pr->p.disk.m) != AP_OK || ap_builder_create("disk", &b) != AP_OK ||
      ap_builder_add_body(b, &bd, NULL) != AP_OK || ap_builder_add_joint(b, &jd, NULL) != AP_OK ||
      ap_builder_add_constraint(b, &cd, NULL) != AP_OK ||
      ap_builder_add_effect(b, &ed, NULL) != AP_OK ||
      ap_builder_compile(b, &pr->body_model) != AP_OK ||
      ap_data_create(pr->body_model, &d) != AP_OK) {
    fprintf(stderr, "bench_wp: rolling disk: %s\n", b ? ap_builder_message(b) : "no builder");
    exit(1);
  }
  ap_builder_free(b);
  const double *e = pr->euler;
  double cp = cos(e[2]), sp = sin(e[2]), ct = cos(e[3]), st = sin(e[3]);
  double l1[3] = {cp, sp, 0.0}, l2[3] = {-ct * sp, ct * cp, st}, l3[3] = {st * sp, -st * cp, ct};
  double R[9], quat[4];
  for (int i = 0; i < 3; i++) R[i] = l1[i], R[3 + i] = -l3[i], R[6 + i] = l2[i];
  ap_quat_from_matrix(R, quat);
  pr->q0[0] = e[0], pr->q0[1] = e[1];
  memcpy(pr->q0 + 2, quat, sizeof quat);
  for (int i = 0; i < 3; i++) pr->v0[2 + i] = e[4] * l1[i] + e[5] * l2[i] + e[6] * l3[i];
  int given[5] = {0, 0, 1, 1, 1};
  d->t = 0.0;
  if (ap_body_complete_speeds(pr->body_model, d, pr->q0, given, pr->v0) != AP_OK) {
    fprintf(stderr, "bench_wp: rolling disk: %s\n", d->msg);
    exit(1);
  }
  ap_data_free(d);
  pr->n = ap_model_n(pr->body_model), pr->k = ap_model_k(pr->body_model);
}

/* The disk's reference: its hand ODE at rtol = atol = 1e-14 (fehlberg8). */
static void disk_reference(wp_problem *pr) {
  ap_step_opts o;
  memset(&o, 0, sizeof o);
  o.rtol = o.atol = 1e-14, o.max_steps = 100000000;
  ap_stepper *st = NULL;
  double y[MAXS], t = 0.0;
  char msg[256];
  if (ap_step_create(ap_step_method_find("fehlberg8"), pr->hn, pr->hand, pr, 0.0, pr->hy0, &o,
                     &st, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "bench_wp: rolling disk reference: %s\n", msg);
    exit(1);
  }
  for (int i = 0; i < NOUT; i++) {
    double tout = pr->T * (i + 1) / NOUT;
    while (t < tout)
      if (ap_step_one(st, tout, &t, y) != AP_OK) {
        fprintf(stderr, "bench_wp: rolling disk reference: %s\n", ap_step_message(st));
        exit(1);
      }
    pr->epos[i][0] = y[0], pr->epos[i][1] = y[1];
  }
  ap_step_free(st);
}

/* The six problems, set up in place (the system callbacks keep a pointer to pr->p). */
static void setup_problems(wp_problem *P) {
  memset(P, 0, sizeof(wp_problem) * NPROB);
  wp_problem *pr = &P[0];  /* knife: spins through phi = pi/2 (partition switches) */
  pr->name = "knife_edge", pr->title = "knife edge on an incline (k 3, b 1)";
  pr->p.knife = (rs_knife){.m = 2.0, .J = 0.3, .grav = 9.81, .alpha = 0.4};
  rs_knife_system(&pr->p.knife, &pr->def);
  rs_knife_initial(0.0, 0.0, 0.3, 1.0, 2.0, pr->q0, pr->v0);
  pr->T = 10.0, pr->npos = 2, pr->hn = 5, pr->hand = knife_hand;
  double hk[5] = {0.0, 0.0, 0.3, 1.0, 2.0};
  memcpy(pr->hy0, hk, sizeof hk);

  pr = &P[1];              /* sleigh: turns about 2 rad, then runs straight */
  pr->name = "sleigh", pr->title = "Chaplygin sleigh (k 3, b 1)";
  pr->p.sleigh = (rs_sleigh){.m = 1.0, .I = 1.0, .a = 1.0};
  rs_sleigh_system(&pr->p.sleigh, 1, &pr->def);
  rs_sleigh_initial(0.0, 0.0, 0.0, 0.5, 2.0, pr->q0, pr->v0);
  pr->T = 6.0, pr->npos = 2, pr->hn = 5, pr->hand = sleigh_hand;
  double hs[5] = {0.0, 0.0, 0.0, 0.5, 2.0};
  memcpy(pr->hy0, hs, sizeof hs);

  for (int v = 0; v < 2; v++) {  /* turntable: about 1.5 turns of the centre's circle */
    pr = &P[2 + v];
    pr->name = v ? "turntable_var" : "turntable";
    pr->title = v ? "ball on a turntable, Omega(t) = 0.5 + 0.1 t (k 5, b 2, rheonomic)"
                  : "ball on a turntable, Omega = 2 (k 5, b 2, affine)";
    pr->p.turn = v ? (rs_turntable){.m = 1.0, .R = 0.1, .kI = 0.4, .Omega0 = 0.5, .dOmega = 0.1}
                   : (rs_turntable){.m = 1.0, .R = 0.1, .kI = 0.4, .Omega0 = 2.0, .dOmega = 0.0};
    rs_turntable_system(&pr->p.turn, &pr->def);
    rs_turntable_initial(&pr->p.turn, 0.3, -0.1, 1.0, -2.0, 3.0, pr->q0, pr->v0);
    pr->T = 16.0, pr->npos = 2, pr->hn = 4, pr->hand = turn_hand;
    double ht[4] = {pr->q0[0], pr->q0[1], pr->v0[0], pr->v0[1]};
    memcpy(pr->hy0, ht, sizeof ht);
  }

  pr = &P[4];              /* line: the bead falls in, crosses the origin, and flies out */
  pr->name = "rotating_line", pr->title = "bead on a rotating line, 3-D (k 3, b 2, rheonomic)";
  pr->p.line = (rs_line){.m = 1.0, .grav = 9.81, .alpha = 0.6, .w = 2.0};
  rs_line_3d_system(&pr->p.line, &pr->def);
  pr->r0 = 6.0, pr->rd0 = 0.2;
  rs_line_lift(&pr->p.line, 0.0, pr->r0, pr->rd0, pr->q0, pr->v0);
  pr->T = 4.0, pr->npos = 3, pr->hn = 2, pr->hand = line_hand;
  pr->hy0[0] = pr->r0, pr->hy0[1] = pr->rd0;

  pr = &P[5];              /* disk: leaning 10 degrees, spinning and turning; wobbles */
  pr->name = "rolling_disk";
  pr->title = "rolling disk, body model (n 6, k 5, b 2; reference: hand ODE at 1e-14)";
  pr->p.disk.m = 1.0, pr->p.disk.r = 0.5, pr->p.disk.grav = 9.81;
  double th0 = 10.0 * RS_PI / 180.0, psid0 = 1.0, phid0 = -6.0;
  double eu[7] = {0.0, 0.0, 0.0, th0, 0.0, phid0 + psid0 * sin(th0), psid0 * cos(th0)};
  memcpy(pr->euler, eu, sizeof eu);
  pr->T = 6.0, pr->npos = 2, pr->hn = 7, pr->hand = disk_hand;
  memcpy(pr->hy0, eu, sizeof eu);
  disk_setup(pr);

  for (int i = 0; i < NPROB; i++) {
    if (!P[i].body_model) P[i].n = P[i].def.n, P[i].k = P[i].def.k;
    P[i].pos_q = pos_first;
    P[i].pos_hand = i == 4 ? line_pos_hand : pos_first;
    if (i < 5) fill_exact(&P[i], i);
    else disk_reference(&P[i]);
  }
}

static void free_problems(wp_problem *P) {
  for (int i = 0; i < NPROB; i++) ap_model_free(P[i].body_model);
}

/* ---- runs --------------------------------------------------------------------------------- */

typedef struct wp_run {
  const char *tool;         /* "appell" or "hand" */
  const char *mode;         /* "minimal", "projected", "dae"; "reduced" for hand */
  const char *method;       /* stepper name; "ida" in DAE mode */
  double tol;               /* rtol = atol (adaptive), 0 for fixed step */
  double h;                 /* fixed step (rk4), 0 for adaptive */
} wp_run;

typedef struct wp_result {
  int status;
  double err;               /* max position error over the outputs (m) */
  long steps, evals, fails;
  double resid;             /* largest |A v + a0| at step ends (Appell) */
  double cpu, lo, hi;       /* CPU seconds: median, min, max */
  int reps;
  char msg[200];
} wp_result;

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double pos_err(const wp_problem *pr, int i, const double *pos) {
  double e = 0.0;
  for (int c = 0; c < pr->npos; c++) e = fmax(e, fabs(pos[c] - pr->epos[i][c]));
  return isfinite(e) ? e : INFINITY;
}

/* One Appell run: create the simulation, advance through the outputs, free. */
static int run_appell(const wp_problem *pr, const ap_model *m, const wp_run *r, wp_result *res) {
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = !strcmp(r->mode, "minimal") ? AP_MODE_MINIMAL
            : !strcmp(r->mode, "projected") ? AP_MODE_PROJECTED : AP_MODE_DAE;
  sd.method = r->method;
  if (r->h > 0) sd.h_fixed = r->h;
  else sd.rtol = sd.atol = r->tol;
  sd.max_steps = WP_MAX_STEPS;
  ap_sim *s = NULL;
  int rc = ap_sim_create(m, &sd, 0.0, pr->q0, pr->v0, &s, res->msg, sizeof res->msg);
  if (rc != AP_OK) return rc;
  double err = 0.0, pos[3];
  for (int i = 0; i < NOUT && rc == AP_OK; i++) {
    double t = pr->T * (i + 1) / NOUT;
    rc = ap_sim_advance(s, t);
    if (rc != AP_OK) {
      snprintf(res->msg, sizeof res->msg, "%s", ap_sim_message(s));
      break;
    }
    pr->pos_q(pr, t, ap_sim_q(s), pos);
    err = fmax(err, pos_err(pr, i, pos));
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  res->err = err, res->steps = st.steps, res->evals = st.rhs_evals, res->fails = st.err_fails;
  res->resid = st.max_residual;
  ap_sim_free(s);
  return rc;
}

/* One run of the hand-reduced ODE under the same stepper. */
static int run_hand(const wp_problem *pr, const wp_run *r, wp_result *res) {
  const ap_step_method *meth = ap_step_method_find(r->method);
  if (!meth) return AP_ERR_ARG;
  ap_step_opts o;
  memset(&o, 0, sizeof o);
  if (r->h > 0) o.h_fixed = r->h;
  else o.rtol = o.atol = r->tol;
  o.max_steps = WP_MAX_STEPS;
  ap_stepper *st = NULL;
  double y[MAXS], t = 0.0, err = 0.0, pos[3];
  int rc = ap_step_create(meth, pr->hn, pr->hand, (void *)pr, 0.0, pr->hy0, &o, &st, res->msg,
                          sizeof res->msg);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < NOUT && rc == AP_OK; i++) {
    double tout = pr->T * (i + 1) / NOUT;
    while (t < tout && rc == AP_OK) rc = ap_step_one(st, tout, &t, y);
    if (rc != AP_OK) {
      snprintf(res->msg, sizeof res->msg, "%s", ap_step_message(st));
      break;
    }
    pr->pos_hand(pr, tout, y, pos);
    err = fmax(err, pos_err(pr, i, pos));
  }
  ap_step_stats ss;
  ap_step_get_stats(st, &ss);
  res->err = err, res->steps = ss.steps, res->evals = ss.rhs_evals, res->fails = ss.err_fails;
  res->resid = 0.0;
  ap_step_free(st);
  return rc;
}

static int run_once(const wp_problem *pr, const ap_model *m, const wp_run *r, wp_result *res) {
  return !strcmp(r->tool, "hand") ? run_hand(pr, r, res) : run_appell(pr, m, r, res);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Time one configuration: a first timed run; runs under 50 ms are repeated (the first one
 * then counts as warm-up) until about 0.15 s is spent, at least 3 and at most 15 times.
 * Kept out of line: scripts/bench --callgrind collects inside it (--toggle-collect). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static void measure(const wp_problem *pr, const ap_model *m, const wp_run *r, int min_reps,
                    wp_result *res) {
  double ts[64];
  memset(res, 0, sizeof *res);
  double t0 = cpu_now();
  res->status = run_once(pr, m, r, res);
  ts[0] = cpu_now() - t0;
  int n = 1, first = 0;
  if (res->status == AP_OK && (ts[0] < 0.05 || min_reps > 1)) {
    int reps = ts[0] > 0 ? (int)(0.15 / ts[0]) : 15;
    reps = reps < 3 ? 3 : reps > 15 ? 15 : reps;
    if (min_reps > reps) reps = min_reps > 63 ? 63 : min_reps;
    if (ts[0] < 0.05) first = 1;          /* drop the warm-up */
    for (; n < 1 + reps; n++) {
      wp_result tmp;
      memset(&tmp, 0, sizeof tmp);
      t0 = cpu_now();
      run_once(pr, m, r, &tmp);
      ts[n] = cpu_now() - t0;
    }
  }
  qsort(ts + first, (size_t)(n - first), sizeof(double), cmp_double);
  res->reps = n - first;
  res->cpu = ts[first + (n - first) / 2];
  res->lo = ts[first];
  res->hi = ts[n - 1];
}

/* ---- the sweep ------------------------------------------------------------------------------ */

static const char *const adaptive_methods[] = {"bs3", "dopri5", "verner6", "fehlberg8",
                                               "dop853", "adams", "bdf"};
#define NADAPT 7
#define NTOL 10     /* 1e-3 ... 1e-12 */
#define NFIX 12     /* rk4: h = T / (NOUT m), m = 2 ... 4096 */

static void print_row(FILE *out, const wp_problem *pr, const wp_run *r, const wp_result *res) {
  if (!out) return;
  fprintf(out, "%s,%s,%s,%s,%.3g,%.6g,%d,%.6e,%.6e,%.6e,%.6e,%d,%ld,%ld,%ld,%.4f,%.3e\n",
          pr->name, r->tool, r->mode, r->method, r->tol, r->h, res->status, res->err, res->cpu,
          res->lo, res->hi, res->reps, res->steps, res->evals, res->fails,
          res->evals > 0 ? 1e6 * res->cpu / res->evals : 0.0, res->resid);
  fflush(out);
}

/* One curve: tightening tolerances (or halving steps) until a run costs more than budget,
 * the error reaches 1e-13, or runs fail at three settings in a row (loose settings may fail
 * where tight ones work: the disk tips over flat in an oversized trial step). */
static void sweep_curve(FILE *out, const wp_problem *pr, const ap_model *m, wp_run r,
                        double budget, int quick) {
  int npts = r.h > 0 || !strcmp(r.method, "rk4") ? NFIX : NTOL, fails = 0;
  for (int i = 0; i < npts; i += quick ? 3 : 1) {
    if (!strcmp(r.method, "rk4")) r.h = pr->T / (NOUT * (double)(2 << i)), r.tol = 0.0;
    else r.tol = pow(10.0, -3 - i);
    wp_result res;
    measure(pr, m, &r, 1, &res);
    print_row(out, pr, &r, &res);
    printf("  %-9s %-6s %-10s %-9s %8.1e %8.2e %9.3e s %4d %8ld %9ld %6.3f us/eval%s%s\n",
           pr->name, r.tool, r.mode, r.method, r.h > 0 ? r.h : r.tol, res.err, res.cpu,
           res.reps, res.steps, res.evals, res.evals ? 1e6 * res.cpu / res.evals : 0.0,
           res.status ? "  FAILED: " : "", res.status ? res.msg : "");
    fflush(stdout);
    if (res.status != AP_OK && res.steps == 0) break;   /* refused (e.g. unsupported mode) */
    fails = res.status != AP_OK ? fails + 1 : 0;
    if (fails >= 3 || res.cpu > budget || (res.status == AP_OK && res.err < 1e-13)) break;
  }
}

/* The disk's reference confirmed by Appell: minimal mode (fehlberg8, 1e-13) and DAE mode
 * (IDA, 1e-10) against it, and the energy drift of the minimal run (rolling does no work). */
static void disk_check(const wp_problem *pr, const ap_model *m) {
  static const char *const modes[] = {"minimal", "dae"};
  for (int i = 0; i < 2; i++) {
    wp_run r = {"appell", modes[i], i ? "ida" : "fehlberg8", i ? 1e-10 : 1e-13, 0};
    wp_result res;
    memset(&res, 0, sizeof res);
    int rc = run_appell(pr, m, &r, &res);
    printf("  reference check: Appell %s %s rtol %.0e: max |centre - reference| = %.2e m%s%s\n",
           r.mode, r.method, r.tol, res.err, rc ? ", FAILED: " : "", rc ? res.msg : "");
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.method = "fehlberg8", sd.rtol = sd.atol = 1e-13;
  ap_sim *s = NULL;
  double T0, V0, T1, V1;
  if (ap_sim_create(m, &sd, 0.0, pr->q0, pr->v0, &s, NULL, 0) != AP_OK) return;
  ap_data *d = (ap_data *)ap_sim_data(s);
  int ok = ap_body_energy(m, d, &T0, &V0) == AP_OK && ap_sim_advance(s, pr->T) == AP_OK &&
           ap_body_energy(m, d, &T1, &V1) == AP_OK;
  if (ok)
    printf("  reference check: energy %.15g J at t = 0, drift %.2e J at t = %g\n", T0 + V0,
           T1 + V1 - T0 - V0, pr->T);
  ap_sim_free(s);
}

static void sweep_problem(FILE *out, const wp_problem *pr, double budget, int quick) {
  ap_model *m = NULL;
  char msg[256];
  double t0 = cpu_now();
  if (pr->body_model) m = pr->body_model;
  else if (ap_model_from_system(&pr->def, &m, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "bench_wp: %s: %s\n", pr->name, msg);
    exit(1);
  }
  if (pr->body_model) printf("%s: %s, T = %g s\n", pr->name, pr->title, pr->T);
  else
    printf("%s: %s, T = %g s, model compiled in %.1f us\n", pr->name, pr->title, pr->T,
           1e6 * (cpu_now() - t0));
  if (pr->body_model) disk_check(pr, m);
  static const char *const modes[] = {"minimal", "projected"};
  for (int md = 0; md < 2; md++) {
    for (int j = 0; j <= NADAPT; j++) {
      wp_run r = {"appell", modes[md], j < NADAPT ? adaptive_methods[j] : "rk4", 0, 0};
      sweep_curve(out, pr, m, r, budget, quick);
    }
  }
  wp_run dae = {"appell", "dae", "ida", 0, 0};
  sweep_curve(out, pr, m, dae, budget, quick);
  for (int j = 0; j <= NADAPT; j++) {
    wp_run r = {"hand", "reduced", j < NADAPT ? adaptive_methods[j] : "rk4", 0, 0};
    sweep_curve(out, pr, m, r, budget, quick);
  }
  if (!pr->body_model) ap_model_free(m);
}

/* ---- problem descriptions for the peers ------------------------------------------------------ */

static void describe(FILE *f, const wp_problem *P) {
  fprintf(f, "# bench_wp problem descriptions: name key values...; exact rows: t pos...\n");
  for (int i = 0; i < NPROB; i++) {
    const wp_problem *pr = &P[i];
    fprintf(f, "%s T %.17g\n%s nout %d\n%s npos %d\n", pr->name, pr->T, pr->name, NOUT,
            pr->name, pr->npos);
    switch (i) {
      case 0:
        fprintf(f, "%s param m %.17g J %.17g grav %.17g alpha %.17g\n", pr->name,
                pr->p.knife.m, pr->p.knife.J, pr->p.knife.grav, pr->p.knife.alpha);
        break;
      case 1:
        fprintf(f, "%s param m %.17g I %.17g a %.17g\n", pr->name, pr->p.sleigh.m,
                pr->p.sleigh.I, pr->p.sleigh.a);
        break;
      case 2:
      case 3:
        fprintf(f, "%s param m %.17g R %.17g kI %.17g Omega0 %.17g dOmega %.17g\n", pr->name,
                pr->p.turn.m, pr->p.turn.R, pr->p.turn.kI, pr->p.turn.Omega0, pr->p.turn.dOmega);
        break;
      case 4:
        fprintf(f, "%s param m %.17g grav %.17g alpha %.17g w %.17g\n", pr->name,
                pr->p.line.m, pr->p.line.grav, pr->p.line.alpha, pr->p.line.w);
        break;
      default:
        fprintf(f, "%s param m %.17g r %.17g grav %.17g\n", pr->name, pr->p.disk.m,
                pr->p.disk.r, pr->p.disk.grav);
        fprintf(f, "%s euler", pr->name);   /* x y psi theta w1 w2 w3, see disk_hand */
        for (int c = 0; c < 7; c++) fprintf(f, " %.17g", pr->euler[c]);
        fprintf(f, "\n");
        break;
    }
    fprintf(f, "%s q0", pr->name);
    for (int c = 0; c < pr->n; c++) fprintf(f, " %.17g", pr->q0[c]);
    fprintf(f, "\n%s v0", pr->name);
    for (int c = 0; c < pr->k; c++) fprintf(f, " %.17g", pr->v0[c]);
    fprintf(f, "\n");
    for (int j = 0; j < NOUT; j++) {
      fprintf(f, "%s exact %.17g", pr->name, pr->T * (j + 1) / NOUT);
      for (int c = 0; c < pr->npos; c++) fprintf(f, " %.17g", pr->epos[j][c]);
      fprintf(f, "\n");
    }
  }
}

/* ---- main ------------------------------------------------------------------------------------ */

static int usage(void) {
  fprintf(stderr, "usage: bench_wp [--csv FILE] [--describe FILE] [--problems a,b,...] "
                  "[--budget S] [--quick]\n"
                  "       bench_wp --one PROBLEM appell|hand MODE METHOD TOL_OR_H [--reps N]\n");
  return 2;
}

static int in_list(const char *list, const char *name) {
  if (!list) return 1;
  size_t n = strlen(name);
  for (const char *p = strstr(list, name); p; p = strstr(p + 1, name))
    if ((p == list || p[-1] == ',') && (p[n] == ',' || p[n] == '\0')) return 1;
  return 0;
}

/* --one: a single configuration repeated reps times (for callgrind and perf). */
static int run_one(const wp_problem *P, char **a, int reps) {
  for (int i = 0; i < NPROB; i++) {
    if (strcmp(P[i].name, a[0])) continue;
    wp_run r = {a[1], a[2], a[3], 0, 0};
    if (!strcmp(a[3], "rk4")) r.h = atof(a[4]);
    else r.tol = atof(a[4]);
    ap_model *m = P[i].body_model;
    if (!m && ap_model_from_system(&P[i].def, &m, NULL, 0) != AP_OK) return 1;
    wp_result res;
    measure(&P[i], m, &r, reps, &res);
    printf("%s %s %s %s: err %.3e, median %.4e s over %d, %ld steps, %ld evals, "
           "%.3f us/eval%s%s\n", a[0], a[1], a[2], a[3], res.err, res.cpu, res.reps, res.steps,
           res.evals, res.evals ? 1e6 * res.cpu / res.evals : 0.0,
           res.status ? ", FAILED: " : "", res.status ? res.msg : "");
    if (m != P[i].body_model) ap_model_free(m);
    return res.status != AP_OK;
  }
  fprintf(stderr, "bench_wp: no problem '%s'\n", a[0]);
  return 2;
}

int main(int argc, char **argv) {
  static wp_problem P[NPROB];
  const char *csv = NULL, *desc = NULL, *list = NULL;
  char **one = NULL;
  double budget = 0.4;
  int quick = 0, reps = 1;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--describe") && i + 1 < argc) desc = argv[++i];
    else if (!strcmp(argv[i], "--problems") && i + 1 < argc) list = argv[++i];
    else if (!strcmp(argv[i], "--budget") && i + 1 < argc) budget = atof(argv[++i]);
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--quick")) quick = 1;
    else if (!strcmp(argv[i], "--one") && i + 5 < argc) one = argv + i + 1, i += 5;
    else return usage();
  }
  if (!(budget > 0) || reps < 1) return usage();
  setup_problems(P);
  if (one) {
    int rc = run_one(P, one, reps);
    free_problems(P);
    return rc;
  }
  if (desc) {
    FILE *f = fopen(desc, "w");
    if (!f) {
      fprintf(stderr, "bench_wp: cannot write %s\n", desc);
      return 1;
    }
    describe(f, P);
    fclose(f);
  }
  FILE *out = NULL;
  if (csv && !(out = fopen(csv, "w"))) {
    fprintf(stderr, "bench_wp: cannot write %s\n", csv);
    return 1;
  }
  if (out)
    fprintf(out, "problem,tool,mode,method,tol,h,status,err,cpu_s,cpu_lo,cpu_hi,reps,steps,"
                 "rhs_evals,err_fails,us_per_eval,residual\n");
  printf("  %-9s %-6s %-10s %-9s %8s %8s %11s %4s %8s %9s %s\n", "problem", "tool", "mode",
         "method", "tol/h", "err", "cpu", "reps", "steps", "evals", "cost");
  for (int i = 0; i < NPROB; i++)
    if (in_list(list, P[i].name)) sweep_problem(out, &P[i], budget, quick);
  if (out) fclose(out);
  free_problems(P);
  return 0;
}
