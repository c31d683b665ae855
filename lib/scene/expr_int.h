/* Scene expressions, inside (expr_parse.c, expr_eval.c, expr_fn.c): the program layout, the
 * operations and the function table. Users include expr.h only. */
#ifndef AP_SCENE_EXPR_INT_H
#define AP_SCENE_EXPR_INT_H

#include "scene/expr.h"

/* Operations of the postfix code. "k" is the constant arg of the instruction, "a" the top of
 * the stack, "b" the entry under it for two-operand operations (b OP a). */
typedef enum sc_op {
  SC_OP_T = 0,     /* push t */
  SC_OP_X,         /* push x[arg] */
  SC_OP_K,         /* push k */
  SC_OP_NEG,       /* a = -a */
  SC_OP_FN,        /* a = fn_arg(a) */
  SC_OP_ADD,       /* b + a (pops one) */
  SC_OP_SUB,       /* b - a */
  SC_OP_MUL,       /* b * a */
  SC_OP_DIV,       /* b / a */
  SC_OP_POW,       /* b ^ a */
  SC_OP_FN2,       /* fn2_arg(b, a) (pops one): atan2, min, max, hypot */
  SC_OP_ADDK,      /* a + k (a - k is stored as a + (-k), which is exact) */
  SC_OP_RSUBK,     /* k - a */
  SC_OP_MULK,      /* a * k */
  SC_OP_DIVK,      /* a / k */
  SC_OP_RDIVK,     /* k / a */
  SC_OP_POWK,      /* a ^ k */
  SC_OP_RPOWK      /* k ^ a */
} sc_op;

/* Does an instruction read the constant k[arg]? */
static inline int sc_op_reads_k(int op) { return op == SC_OP_K || op >= SC_OP_ADDK; }

typedef struct sc_ins {
  unsigned char op;        /* sc_op */
  unsigned char fn;        /* sc_fn of SC_OP_FN */
  unsigned short col;      /* 0-based offset in the text of the operator, name or number */
  int arg;                 /* slot (SC_OP_X) or index into k (SC_OP_K and the ...K ops) */
} sc_ins;

/* One block: the header, then nk constants, nins instructions, nvars slots. */
struct sc_prog {
  int nins, nk, nvars, nx, depth, uses_t;
  const double *k;
  const sc_ins *ins;
  const int *vars;
  double data[];
};

/* The functions of the grammar, in the order of sc_fn_names. */
typedef enum sc_fn {
  SC_FN_EXP = 0, SC_FN_LOG, SC_FN_SQRT, SC_FN_SIN, SC_FN_COS, SC_FN_TAN, SC_FN_COT, SC_FN_SEC,
  SC_FN_CSC, SC_FN_ASIN, SC_FN_ACOS, SC_FN_ATAN, SC_FN_ACOT, SC_FN_ASEC, SC_FN_ACSC,
  SC_FN_SINH, SC_FN_COSH, SC_FN_TANH, SC_FN_COTH, SC_FN_SECH, SC_FN_CSCH, SC_FN_ASINH,
  SC_FN_ACOSH, SC_FN_ATANH, SC_FN_ACOTH, SC_FN_ASECH, SC_FN_ACSCH, SC_FN_ERF, SC_FN_ABS,
  SC_FN_STEP, SC_FN_DELTA, SC_FN_SIGN, SC_FN_FLOOR, SC_FN_COUNT
} sc_fn;

/* The functions of two arguments (expr_fn2.c), in the order of sc_fn2_names; clamp(x, lo, hi)
 * compiles to min(max(x, lo), hi). */
typedef enum sc_fn2 { SC_FN2_ATAN2 = 0, SC_FN2_MIN, SC_FN2_MAX, SC_FN2_HYPOT, SC_FN2_COUNT } sc_fn2;

extern const char *const sc_fn2_names[SC_FN2_COUNT + 2];   /* and "clamp"; NULL-terminated */

extern const char *const sc_fn_names[SC_FN_COUNT + 1];   /* NULL-terminated */

/* expr_fn.c: a function's value, and its jet from the argument's jet (r may alias a). */
double sc_fn_value(int fn, double u);
void sc_fn_jet(int fn, const sc_jet *a, sc_jet *r);
/* expr_fn2.c: fn2(b, a), its value and its jet (r may alias b or a). */
double sc_fn2_value(int fn, double b, double a);
void sc_fn2_jet(int fn, const sc_jet *b, const sc_jet *a, sc_jet *r);
/* Is instruction in a kink (abs, step, delta, sign, floor, min, max)? Its event function's
 * value from the operand(s) b (under the top, two-operand kinks only) and a (the top):
 * the argument of abs, step, delta, sign; b - a for min and max; sin(pi a) for floor (zero
 * at every integer, where floor jumps). */
int sc_is_kink(const sc_ins *in);
double sc_kink_arg(const sc_ins *in, double b, double a);

/* expr_eval.c: one operation (not a push) on values, b the left operand of two-operand
 * operations (ignored by the others) and a the right one: the evaluator's own code, so
 * constants folded at compile time equal what evaluation computes. */
double sc_op_value(const sc_ins *in, const double *k, double b, double a);
/* How many entries an instruction pushes (+1), pops (-1) or leaves (0). */
int sc_op_push(int op);

#endif
