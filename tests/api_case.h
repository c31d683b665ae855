/* tests/test_api's cases (api_cases_low.c: status, systems, core, simulations, builder;
 * api_cases_high.c: body queries, scenes, runs, batches, linearization), its case registry
 * and its fixtures (test_api.c). A case is one call with NULL or out-of-range arguments and the
 * result its header documents (see test_api.c). */
#ifndef APPELL_API_CASE_H
#define APPELL_API_CASE_H

#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "bodysys.h"

#define MAXCASE 1024
extern int pick;                 /* the case a child runs; -1 in the parent (listing) */
extern int ncase;
extern const char *case_fn[MAXCASE], *case_what[MAXCASE];

/* Registers a case; in the child of case `pick`, evaluates it and exits 0 (as documented)
 * or 3 (another result). */
#define CASE(fn, what, ...)                                                              \
  do {                                                                                   \
    if (ncase == pick) _exit((__VA_ARGS__) ? 0 : 3);                                     \
    if (ncase < MAXCASE) case_fn[ncase] = #fn, case_what[ncase] = what;                 \
    ncase++;                                                                             \
  } while (0)

/* The fixtures (test_api.c's fixtures(), made once in the parent, inherited by each child). */
extern ap_model *BM, *TM, *SM;   /* rolling disk (body model, b = 2), heavy top, sleigh (math) */
extern ap_data *BD, *TD, *SD;    /* their data; TD is the wrong data for BM and SM */
extern ap_sim *S;                /* the disk, minimal mode */
extern ap_scene *SC;             /* a sleigh scene (n = k = 3: S is not its simulation) */
extern ap_builder *B;            /* one body, nothing else */
extern ap_scene_out *O;          /* a run's outputs of SC */
extern ap_plan *PL;              /* one grid: bodies.sleigh.mass = 1, 1.5, 2 */
extern ap_batch *BT;             /* a batch of SC's text */
extern ap_lin *LN;               /* a linearizer of the heavy top (not linearized) */
extern char SCENE_PATH[4096];
extern const char SCENE[];       /* the sleigh scene's text */
/* Arguments and outputs the cases share. */
extern double q[8], v[8], w[64], row[64], T, V, E;
extern const double axis[3], qa[4];
extern char msg[256];
extern const double *lam;
extern ap_model *om;
extern ap_data *od;
extern ap_sim *os;
extern ap_scene *osc;
extern ap_builder *ob;
extern ap_method_info mi;
extern ap_batch *obt;
extern ap_lin *oln;
extern ap_lin_eig eg;
extern ap_lin_sweep sw;
extern ap_scene_out *oo;
extern ap_scene_lin sl;
extern ap_scene_lin_guess lg;
extern int stat_[4];
extern char *msgs[4];
extern const double sweep_p[3];
extern ap_body_state bst;
extern ap_contact_force cf;
extern ap_crosscheck_report rep;
extern ap_scene_run run;
extern ap_sim_stats st;
extern int id, given[8];

static inline int all_zero(const void *p, size_t n) {
  const unsigned char *c = p;
  for (size_t i = 0; i < n; i++)
    if (c[i]) return 0;
  return 1;
}
static inline ap_joint_def joint(ap_joint_kind kind, int parent, int child) {
  ap_joint_def j = ap_joint_def_default();
  j.kind = kind, j.parent = parent, j.child = child;
  return j;
}

/* m says that a definition of type `type` (e.g. "ap_joint_def") was refused because its
 * *_default() function did not make it, naming it as `name` when not NULL. */
static inline int not_default_msg(const char *m, const char *type, const char *name) {
  char want[160];
  if (name) snprintf(want, sizeof want, "%s '%s' was not made by %s_default()", type, name, type);
  else snprintf(want, sizeof want, "was not made by %s_default()", type);
  return m && strstr(m, type) != NULL && strstr(m, want) != NULL;
}

/* The sleigh's math-level definition (api_cases_low.c; valid with n = k = 3, b = 1). */
ap_system_def sysdef(int n, int k, int b);

/* The two halves of the cases, in registration order. */
void api_cases_low(void);
void api_cases_high(void);
void api_cases_io(void);      /* api_cases_io.c: output files (outfile.h) */
void api_cases_ctrl(void);    /* api_cases_ctrl.c: inputs and controllers (control.h) */

#endif
