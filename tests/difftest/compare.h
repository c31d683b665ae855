/* The differential tester's comparer (docs/testing.md): one scene run in every mode, path and
 * stepper, against one reference run, with bounds derived from the runs' tolerances. */
#ifndef AP_DIFFTEST_COMPARE_H
#define AP_DIFFTEST_COMPARE_H

enum { DT_AGREE = 0, DT_REFUSED = 1, DT_STOPPED = 2, DT_DISAGREE = 3 };
enum { DT_NCHECK = 6 };   /* kinds of check: initial v, initial v', trajectory, energy,
                             residual, switch time */
extern const char *const dt_check_names[DT_NCHECK];

typedef struct dt_opts {
  int nmethods;
  const char *methods[4];  /* steppers of the Appell modes (DAE is IDA) */
  double rtol, atol;       /* of the compared runs */
  double rtol_ref, atol_ref; /* of the reference (projected, dense, dop853) */
  int expect_tree;         /* 1: the tree path must take the model, 0: must refuse, -1: either */
  int verbose;
} dt_opts;

typedef struct dt_result {
  int verdict;             /* DT_AGREE ... DT_DISAGREE */
  int runs;                /* simulations made */
  int refused_runs;        /* documented refusals of one mode (plain with manifold rows, ...) */
  double worst;            /* largest difference / bound over all checks that ran */
  char worst_what[160];    /* which check that was */
  double worst_by[DT_NCHECK]; /* the same per kind of check (dt_check_names) */
  char what[2048];         /* the disagreements, or why the model was refused or stopped */
} dt_result;

dt_opts dt_opts_default(void);
/* Run and compare the scene text (len bytes). */
void dt_check(const char *text, const dt_opts *o, dt_result *r);

#endif
