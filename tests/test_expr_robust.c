/* test_expr_robust: the scene expression evaluator (lib/scene/expr.h) on bad input and under
 * load (its values and derivatives are in test_expr.c): errors with their columns; the deepest
 * nesting the grammar accepts; evaluation from four threads at once; no heap allocation per
 * evaluation; and every allocation failure in compile returned as AP_ERR_NOMEM without a leak. */
#define _GNU_SOURCE
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "alloc.h"
#include "appell/appell.h"
#include "check.h"
#include "scene/expr_int.h"
#include "scene/scene_int.h"

#define EPS DBL_EPSILON
/* ---- errors and their columns ---------------------------------------------------------------- */

static void test_errors(void) {
  static const char *const names[] = {"wl.angle", "wl.rate", NULL};
  static const struct {
    const char *text;
    int allow_t, col;
    const char *phrase;
  } bad[] = {
      {"sin(", 1, 5, "expected a number, a name or '('"},
      {"t'", 1, 2, "unexpected character '''"},
      {"2 t", 1, 3, "expected an operator at column 3"},
      {"\xff", 1, 1, "unexpected byte 0xff"},
      {"x+1", 1, 1, "unknown name 'x'"},
      {"", 1, 1, "got an empty value"},
      {"t.", 1, 2, "unexpected '.'"},
      {"3*.", 1, 3, "unexpected '.' in expression '3*.' (column 3"},
      {"1e999*t", 1, 1, "number '1e999' out of range"},
      {"sinn(t)", 1, 1, "unknown function 'sinn' in expression 'sinn(t)' (column 1 of the value; "
                        "did you mean 'sin'?)"},
      {"2*sin t", 1, 7, "expected '(' after the function name at column 7"},
      {"(t", 1, 3, "expected ')' at column 3"},
      {"t)", 1, 2, "expected an operator at column 2"},
      {"2*t", 0, 3, "the time t is not allowed here"},
      {"1/0", 0, 1, "is not a finite number"},
      {"log(0)", 0, 1, "is not a finite number"},
      {"wl.rat*2", 1, 1, "unknown name 'wl.rat' in expression 'wl.rat*2' (column 1 of the value; "
                         "did you mean 'wl.rate'?)"},
      {"3 + wl", 1, 5, "unknown name 'wl'"},
      {"wl.rate.x", 1, 1, "unknown name 'wl.rate.x'"},
      {"wl.rate(2)", 1, 1, "unknown function 'wl.rate'"},
      {"t*(2 + q", 1, 9, "expected ')' at column 9"},   /* grammar errors before names */
      {"atan2(t)", 1, 1, "atan2 takes 2 arguments, not 1"}, {"max", 1, 4, "'(' after the function"},
      {"sin(t, 1)", 1, 1, "sin takes 1 argument, not 2"}, {"min(t,)", 1, 7, "expected a number"},
      {"clamp(t, 1)", 1, 1, "clamp takes 3 arguments, not 2"}, {"mix(t, 1)", 1, 1, "mean 'min'?"},
      {"min(t 1)", 1, 7, "expected ')' or ','"},
  };
  /* Nothing is printed (libmatheval echoed stray characters to standard output). */
  fflush(stdout);
  int saved = dup(1);
  FILE *sink = tmpfile();
  if (sink) dup2(fileno(sink), 1);
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    sc_symtab sym = {bad[i].allow_t, names, NULL, NULL, NULL, NULL};
    sc_prog *p = (sc_prog *)&sym;
    sc_prog_err err;
    AP_CHECK_EQ_INT(sc_prog_compile(bad[i].text, &sym, &p, &err), AP_ERR_ARG);
    AP_CHECK(p == NULL && err.status == AP_ERR_ARG);
    AP_CHECK_EQ_INT(err.col, bad[i].col);
    if (!strstr(err.msg, bad[i].phrase) || err.col != bad[i].col)
      fprintf(stderr, "  '%s': expected '%s' at column %d\n  got: %s (column %d)\n", bad[i].text,
              bad[i].phrase, bad[i].col, err.msg, err.col);
    AP_CHECK(strstr(err.msg, bad[i].phrase) != NULL);
  }
  fflush(stdout);
  if (sink) {
    long printed = lseek(1, 0, SEEK_END);
    dup2(saved, 1);
    AP_CHECK_EQ_INT(printed, 0);
    fclose(sink);
  }
  close(saved);
  char longer[SC_EXPR_MAX + 8];
  memset(longer, 't', sizeof longer - 1);
  longer[sizeof longer - 1] = '\0';
  sc_prog *p = NULL;
  sc_prog_err err;
  AP_CHECK_EQ_INT(sc_prog_compile(longer, NULL, &p, &err), AP_ERR_ARG);
  AP_CHECK(strstr(err.msg, "longer than 1000 characters") != NULL);
  /* Through the scene layer: FILE:LINE:COLUMN: key.path: message. */
  sc_ctx c = {"expr", "", AP_OK};
  sc_node at = {.kind = SC_SCALAR, .text = "2*w*t", .line = 3, .col = 14, .path = "ground.omega"};
  sc_expr e;
  AP_CHECK_EQ_INT(sc_expr_compile(&c, &at, at.text, 1, &e), AP_ERR_ARG);
  AP_CHECK(strstr(c.msg, "expr:3:14: ground.omega: unknown name 'w' in expression '2*w*t' "
                         "(column 3 of the value") != NULL);
}

/* The deepest nesting accepted fits the evaluation stack; one level more is refused. */
static void test_nesting(void) {
  char text[1024] = "";
  for (int levels = 99; levels <= 100; levels++) {
    size_t n = 0;
    for (int i = 0; i < levels; i++) n += (size_t)snprintf(text + n, sizeof text - n, "t+t*(");
    n += (size_t)snprintf(text + n, sizeof text - n, "t");
    for (int i = 0; i < levels; i++) text[n++] = ')';
    text[n] = '\0';
    sc_prog *p = NULL;
    sc_prog_err err;
    int rc = sc_prog_compile(text, NULL, &p, &err);
    if (levels == 100) {
      AP_CHECK(rc == AP_ERR_ARG && strstr(err.msg, "expected less nesting") != NULL);
      continue;
    }
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (!p) continue;
    AP_CHECK(p->depth == 2 * levels + 1 && p->depth <= SC_PROG_STACK);
    double t = 0.3, f[3], g[3] = {t, 1, 0};   /* g_{k+1} = t + t g_k, with derivatives */
    for (int i = 0; i < levels; i++)
      g[2] = 2 * g[1] + t * g[2], g[1] = 1 + g[0] + t * g[1], g[0] = t + t * g[0];
    AP_CHECK_EQ_INT(sc_prog_time(p, t, f), 0);
    for (int k = 0; k < 3; k++) AP_CHECK_NEAR(f[k], g[k], 64 * EPS * fabs(g[k]));
    sc_prog_free(p);
  }
}

/* ---- threads, allocations ---------------------------------------------------------------- */

enum { NT = 4, NPTS = 20000 };
static sc_prog *shared;
static double expect[NPTS][3];

static void *worker(void *arg) {
  long bad = 0, id = (long)arg;
  for (int i = 0; i < NPTS; i++) {
    int j = (i * 7 + (int)id * 5003) % NPTS;
    double f[3];
    sc_prog_time(shared, 0.001 * j, f);
    bad += memcmp(f, expect[j], sizeof f) != 0;
  }
  return (void *)bad;
}

static void test_threads(void) {
  sc_prog_err err;
  AP_CHECK_EQ_INT(sc_prog_compile("0.2*exp(-t/4)*cos(3*t + pi/3) + t^2*sin(t)", NULL, &shared,
                                  &err), AP_OK);
  if (!shared) return;
  for (int i = 0; i < NPTS; i++) sc_prog_time(shared, 0.001 * i, expect[i]);
  pthread_t th[NT];
  for (long i = 0; i < NT; i++) AP_CHECK_EQ_INT(pthread_create(&th[i], NULL, worker, (void *)i), 0);
  for (int i = 0; i < NT; i++) {
    void *bad = NULL;
    pthread_join(th[i], &bad);
    AP_CHECK_EQ_INT((long)bad, 0);
  }
  sc_prog_free(shared);
}

static void test_no_allocation(void) {
  static const char *const names[] = {"x", NULL};
  sc_symtab sym = {1, names, NULL, NULL, NULL, NULL};
  sc_prog *p = NULL;
  sc_prog_err err;
  AP_CHECK_EQ_INT(sc_prog_compile("0.2*exp(-t/4)*cos(3*t + x) + log(t)", &sym, &p, &err), AP_OK);
  sc_ctx c = {"expr", "", AP_OK};
  sc_node at = {.kind = SC_SCALAR, .text = "2*tanh(t) + t^2", .line = 1, .col = 1, .path = "x"};
  sc_expr e;
  AP_CHECK_EQ_INT(sc_expr_compile(&c, &at, at.text, 1, &e), AP_OK);
  if (!p) return;
  long before = n_alloc;
  double sum = 0, f[3], xv = 0.5;
  sc_jet tj = {{0, 1, 0}}, xj = {{0.5, 1, 0}}, r;
  char why[128];
  for (int i = 0; i < 1000; i++) {
    tj.c[0] = 0.001 * i - 0.5;   /* log(t) is not finite for t <= 0: explain runs too */
    sc_prog_value(p, tj.c[0], &xv, f);
    sc_prog_jet(p, &tj, &xj, &r);
    sc_prog_explain(p, &tj, &xj, 2, why, sizeof why);
    sc_expr_eval(&e, tj.c[0], f);
    sc_expr_time_fn(tj.c[0], f, &e);
    sum += isfinite(f[0]) ? f[0] : 1.0;
  }
  if (AP_COUNT_ALLOC) AP_CHECK_EQ_INT(n_alloc - before, 0);
  else printf("allocation count not taken (AddressSanitizer owns malloc)\n");
  AP_CHECK(sum != 0.0);
  sc_prog_free(p);
  sc_expr_free(&e);
}

/* Make the i-th allocation of a compile fail, for every i: AP_ERR_NOMEM, nothing leaked. */
static void test_allocation_failures(void) {
  if (!AP_COUNT_ALLOC) return (void)printf("allocation failures not injected (AddressSanitizer)\n");
  static const char *const names[] = {"wl.rate", NULL};
  sc_symtab sym = {1, names, NULL, NULL, NULL, NULL};
  static const char *const texts[] = {"0.2*exp(-t/4)*cos(3*t + pi/3)", "wl.rate*t", "1/0",
                                      "sinn(t)", "2*pi"};
  int injected = 0;
  for (size_t k = 0; k < sizeof texts / sizeof texts[0]; k++)
    for (int wrapper = 0; wrapper < 2; wrapper++)
      for (long i = 0;; i++) {
        long live = n_live;
        sc_prog *p = NULL;
        sc_prog_err err;
        sc_ctx c = {"expr", "", AP_OK};
        sc_node at = {.kind = SC_SCALAR, .text = (char *)texts[k], .line = 1, .col = 1,
                      .path = "x"};
        sc_expr e;
        ap_alloc_fail_at(i);
        int rc = wrapper ? sc_expr_compile_sym(&c, &at, texts[k], &sym, &e)
                         : sc_prog_compile(texts[k], &sym, &p, &err);
        int failed = ap_alloc_failed;
        ap_alloc_fail_at(-1);
        if (!failed) {   /* every allocation of this compile has been made to fail once */
          if (wrapper) sc_expr_free(&e);
          sc_prog_free(p);
          break;
        }
        injected++;
        AP_CHECK_EQ_INT(rc, AP_ERR_NOMEM);
        if (wrapper) AP_CHECK(c.status == AP_ERR_NOMEM && strstr(c.msg, "out of memory") != NULL);
        else AP_CHECK(p == NULL && err.status == AP_ERR_NOMEM);
        AP_CHECK_EQ_INT(n_live, live);
      }
  printf("allocation failures injected: %d, each AP_ERR_NOMEM\n", injected);
  AP_CHECK(injected >= 12);
}

int main(void) {
  test_errors();
  test_nesting();
  test_threads();
  test_no_allocation();
  test_allocation_failures();
  return ap_check_finish("test_expr_robust");
}
