/* Scene expressions (internal): an evaluator of our own for the grammar of docs/scenes.md
 * "Expressions", with exact first and second derivatives by second-order Taylor jets.
 *
 * sc_prog_compile turns text into an immutable program (postfix code and a constant pool in
 * one block): constant subexpressions are folded, names are resolved against a symbol table
 * (t, and variables mapped to slots of a vector x). The program is never written after
 * compile, so any number of threads may evaluate one program at once; evaluation allocates
 * nothing (its stack lives on the caller's C stack, at most SC_PROG_STACK jets = 6 KiB), never
 * prints, never exits. Every evaluation call returns 0 when all its outputs are finite and
 * -1 otherwise (the outputs are written either way); sc_prog_explain then says which
 * operation, at which column of the text, first gave a value that is not finite.
 *
 * Jets: a jet is (c[0], c[1], c[2]) = (f, f', f''/2): TAYLOR COEFFICIENTS, so the third number
 * is HALF the second derivative. Evaluating on jets pushes them through every operation by
 * the chain rule truncated at second order, which is exact (no symbolic differentiation, no
 * finite differences). Seeding:
 *   t = (t, 1, 0), every x_j = (x_j, 0, 0)       -> (f, df/dt, d2f/dt2 / 2) at fixed x
 *   t = (t, 0, 0), x_i = (x_i, 1, 0), others 0   -> (f, df/dx_i, d2f/dx_i2 / 2)
 *   t = (t, 1, 0), x_j = (x_j, x_j', x_j''/2)    -> f and its time derivatives along a motion
 *
 * Kinks: abs, step and delta are smooth except where their argument is exactly 0. There the
 * value is abs(0) = 0, step(0) = 1 (libmatheval's convention), delta(0) = +inf (not finite);
 * the derivatives are those of the side the argument's jet enters (the sign of its first
 * non-zero coefficient c[1], else c[2]: along the motion, the side after the kink), 0 when
 * the jet is constant: abs(t - 1) at t = 1 has time derivative +1, abs(1 - t) too (the
 * argument enters u < 0, where abs' = -1, times u' = -1); step has derivative 0 on both
 * sides. The simulation stops exactly at such kinks (scene events, docs/scenes.md "Kinks"),
 * so the one-sided derivative is the one of the piece integrated next. sign, floor, min, max
 * (and clamp, compiled as min(max(...))) are kinks too (expr_fn2.c); at the jumps of sign and
 * floor the JET's value is that of the side being entered too, so there (only there) c[0] of
 * sc_prog_jet differs from sc_prog_value (sign(0) = 0, floor(n) = n). */
#ifndef AP_SCENE_EXPR_H
#define AP_SCENE_EXPR_H

#include <stddef.h>

#define SC_EXPR_MAX 1000      /* longest text accepted (bytes) */
#define SC_PROG_STACK 256     /* evaluation stack (jets); every text the grammar accepts fits */

/* A second-order Taylor jet: c[0] = f, c[1] = f', c[2] = f''/2. */
typedef struct sc_jet {
  double c[3];
} sc_jet;

/* The names an expression may use besides numbers, pi, e, deg and the functions. A name is
 * letters, digits and '_' (not starting with a digit), in dot-separated parts: `wl.rate` is
 * one name. Lookup order: t, the constants, then the table (a table name equal to t, pi, e or
 * deg is never reached; function names are reserved). */
typedef struct sc_symtab {
  int allow_t;                /* 1: the time t may appear */
  const char *const *names;   /* NULL-terminated variable names, or NULL for none */
  const int *slots;           /* slot in x of names[i] (>= 0); NULL: slot i */
  /* Named constants (the scene's parameters, params.c), asked after the variables: returns 1
   * and *value for a name it knows, 0 for one it does not, -1 when the name's own value
   * failed (the caller has the message; the compile then fails). NULL: none. */
  int (*lookup)(void *user, const char *name, size_t len, double *value);
  void *user;                 /* passed to lookup */
  const char *const *constants;   /* lookup's names, for "did you mean" (NULL-terminated) */
} sc_symtab;

typedef struct sc_prog sc_prog;   /* immutable after sc_prog_compile */

typedef struct sc_prog_err {
  int status;                 /* AP_OK, AP_ERR_ARG (the text is not an expression) or
                                 AP_ERR_NOMEM */
  int col;                    /* 1-based column of the text where it was found; 0: none */
  char msg[640];              /* the complete message (quotes the text, names the column) */
} sc_prog_err;

/* Compile text (NUL-terminated, at most SC_EXPR_MAX bytes). On failure *out is NULL and err
 * says why; every allocation failure gives AP_ERR_NOMEM. A constant subexpression that is not
 * finite (`t + 1/0`) is an error here. */
int sc_prog_compile(const char *text, const sc_symtab *sym, sc_prog **out, sc_prog_err *err);
void sc_prog_free(sc_prog *p);

/* What a program uses. */
int sc_prog_uses_t(const sc_prog *p);
int sc_prog_nvars(const sc_prog *p);          /* distinct variable slots used */
const int *sc_prog_vars(const sc_prog *p);    /* those slots, ascending (nvars entries) */
int sc_prog_nx(const sc_prog *p);             /* 1 + the largest slot used (0 when none) */
/* 1 and *value when the program uses neither t nor a variable (it folded to a number). */
int sc_prog_constant(const sc_prog *p, double *value);

/* The kinks (abs, step, delta, sign, floor, min, max) of a program, in the order of its code,
 * and their event functions at (t, x) into args (sc_prog_nkinks entries, sc_kink_arg in
 * expr_int.h: zero exactly at the kink); returns their number. */
int sc_prog_nkinks(const sc_prog *p);
int sc_prog_kinks(const sc_prog *p, double t, const double *x, double *args);
/* The value at (t, x); x may be NULL when the program uses no variable. */
int sc_prog_value(const sc_prog *p, double t, const double *x, double *f);
/* The jet of the expression from the jets of t and of x (x: sc_prog_nx entries, NULL when
 * the program uses no variable). */
int sc_prog_jet(const sc_prog *p, const sc_jet *t, const sc_jet *x, sc_jet *f);
/* For expressions of t only: f[0] = f, f[1] = f', f[2] = f'' (the second derivative itself).
 * A program that uses variables gives NaN and -1. */
int sc_prog_time(const sc_prog *p, double t, double f[3]);

/* Where the evaluation on these jets (x as for sc_prog_jet; order 0: values only, 2: all three
 * coefficients) first gives something not finite, e.g. "log(-1) = nan at column 1"; returns
 * the 1-based column, or 0 (and buf "") when everything is finite. */
int sc_prog_explain(const sc_prog *p, const sc_jet *t, const sc_jet *x, int order, char *buf,
                    size_t len);

#endif
