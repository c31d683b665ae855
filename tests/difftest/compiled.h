/* The differential tester's compiled-model check (difftest --compiled; compiled.c): each
 * model interpreted and compiled (docs/compiled.md), compared. */
#ifndef AP_DIFFTEST_COMPILED_H
#define AP_DIFFTEST_COMPILED_H

#include <stddef.h>

#include "compare.h"

typedef struct dt_cresult {
  int compiled;          /* 1: the model was compiled and compared */
  int interpreted;       /* 1: the generator does not take it (notice) */
  int disagree;
  int runs;              /* simulations made */
  double worst_exact;    /* largest relative difference of q0, v0, v', q' (bound 1e-13) */
  double worst_run;      /* largest state difference / its trajectory bound */
  double worst_run_rel;  /* largest relative difference of the compared states */
  char notice[300];
  char what[1024];       /* the disagreements */
} dt_cresult;

typedef struct dt_ctally {
  long compiled, interpreted, disagree, runs;
  double worst_exact, worst_run, worst_run_rel;   /* over the agreeing models */
  char notice[300];                               /* the first model left interpreted */
} dt_ctally;

void dt_check_compiled(const char *text, const dt_opts *o, dt_cresult *r);
/* r becomes a disagreement (with c's lines) when c is one; its runs count c's. */
void dt_compiled_merge(const dt_cresult *c, dt_result *r);
void dt_compiled_add(dt_ctally *t, const dt_cresult *c);
void dt_compiled_print(const dt_ctally *t);
/* 1 when a model can be compiled here (a C compiler runs), else 0 with why. */
int dt_compiler_works(char *why, size_t len);

#endif
