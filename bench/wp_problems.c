/* bench_wp's problems (wp.h): knife edge, sleigh, turntable (steady and spinning up), rotating
 * line and rolling disk, each as an Appell model and as its hand-reduced ODE, with the exact
 * (or reference) positions at the output times. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bodysys.h"
#include "wp.h"

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
void setup_problems(wp_problem *P) {
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
    pr->ball_model = bs_turntable_model(&pr->p.turn);   /* keeps a pointer to pr->p.turn */
    double bq[6] = {pr->q0[0], pr->q0[1], 1, 0, 0, 0};
    memcpy(pr->bq0, bq, sizeof bq);
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

void free_problems(wp_problem *P) {
  for (int i = 0; i < NPROB; i++) {
    ap_model_free(P[i].body_model), ap_model_free(P[i].ball_model);
    ap_model_free(P[i].ball_compiled);
  }
}
