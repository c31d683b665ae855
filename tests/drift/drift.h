/* The drift suite's systems (drift_systems.c) as the runner (drift.c) sees them: each a setup
 * that builds the model and the initial state, and a measure of its invariants and loop
 * residual along the run. */
#ifndef APPELL_DRIFT_H
#define APPELL_DRIFT_H

#include "bodysys.h"

#define MAXN 8
#define MAXINV 3

typedef struct drift_sys drift_sys;

/* One system set up for a run: its model, a data struct for measurements, the initial state. */
typedef struct sysrun {
  const drift_sys *sys;
  ap_model *m;
  ap_data *d;
  double q0[MAXN], v0[MAXN];
  union {
    rs_knife knife;
    rs_sleigh sleigh;
    rs_turntable table;
    rs_line line;
    rs_hoffmann hoff;
  } p;
  double top[5];        /* heavy top: m, l, A0, C, grav */
  int quat[2], nquat;   /* offsets of the quaternions in q */
} sysrun;

struct drift_sys {
  const char *name;
  const char *group;          /* meson test that runs it */
  unsigned modes;             /* bit (1 << ap_mode) */
  const char *method;
  double rtol;                /* atol = 1e-2 rtol */
  double t_end, dae_t_end;    /* IDA takes 4 to 10 times more steps: a shorter run */
  double h_max;               /* 0 = none; else the run takes t_end / h_max steps at least */
  long min_steps;
  int has_loop;
  int ninv;
  const char *inv[MAXINV];
  double inv_scale[MAXINV];   /* > 0: drift relative to max(|I0|, scale); 0: absolute */
  int (*setup)(sysrun *r);
  /* invariants and, when has_loop, the loop residual at (t, q, v) */
  int (*measure)(sysrun *r, double t, const double *q, const double *v, double *inv,
                 double *loop);
};

#define M_MIN (1u << AP_MODE_MINIMAL)
#define M_PRJ (1u << AP_MODE_PROJECTED)
#define M_PLN (1u << AP_MODE_PLAIN)
#define M_DAE (1u << AP_MODE_DAE)
#define M_ALL (M_MIN | M_PRJ | M_PLN | M_DAE)

/* Every system of the suite, in the order the runner lists them. */
extern const drift_sys drift_systems[];
extern const int drift_nsys;

#endif
