/* bench_wp's problems (wp_problems.c): each an Appell system (math level or a body model), its
 * hand-reduced ODE, the exact positions at the output times and the descriptions the peers'
 * harnesses read. */
#ifndef APPELL_BENCH_WP_H
#define APPELL_BENCH_WP_H

#include "appell/appell.h"
#include "integrate/stepper.h"
#include "refsys.h"

#define NOUT 10        /* output times t_i = i T / NOUT, i = 1 .. NOUT */
#define MAXS 16        /* largest state of any problem */
#define NPROB 6
/* Steps allowed between two output times: a run that needs more fails (and stops its curve)
 * instead of running for minutes (e.g. CVODE restarted after every step). */
#define WP_MAX_STEPS 20000

typedef struct wp_problem wp_problem;
struct wp_problem {
  const char *name, *title;
  ap_system_def def;        /* the Appell math-level system (refsys) */
  ap_model *body_model;     /* or a compiled body model (rolling disk) */
  ap_model *ball_model;     /* turntables: the ball built from bodies (tests/bodysys.c), run
                               beside the math-level system as tool "appell_body" */
  ap_model *ball_compiled;  /* bench_wp --compiled: a second ball switched to compiled
                               kinematics (docs/compiled.md), tool "appell_body_c"; else NULL */
  double bq0[MAXS];         /* its initial coordinates (x, y, unit quaternion); speeds v0 */
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

/* The NPROB problems into P (exact positions computed); free_problems releases the models. */
void setup_problems(wp_problem *P);
void free_problems(wp_problem *P);

#endif
