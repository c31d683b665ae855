/* libFuzzer harness: the expression evaluator (lib/scene/expr.h). The input is an expression's
 * text (cut at SC_EXPR_MAX bytes and at the first NUL).
 *
 * sc_prog_compile with t and two variables (a, b.rate) allowed, then the value, the jets in t
 * and in a variable, sc_prog_time and sc_prog_explain at a few points (0, 1, -2.5, 1e300).
 * A compile failure must come with a message; evaluation must not crash whatever the values.
 * Seeds: tests/fuzz/seeds/expr (scripts/fuzz). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "scene/expr.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char text[SC_EXPR_MAX + 1];
  size_t n = size < SC_EXPR_MAX ? size : SC_EXPR_MAX;
  memcpy(text, data, n);
  text[n] = '\0';
  static const char *const names[] = {"a", "b.rate", NULL};
  sc_symtab sym = {1, names, NULL, NULL, NULL, NULL};
  sc_prog *p = NULL;
  sc_prog_err err;
  if (sc_prog_compile(text, &sym, &p, &err) != AP_OK) {
    if (p || !err.msg[0]) abort();   /* a failure has no program and a message */
    return 0;
  }
  static const double ts[] = {0.0, 1.0, -2.5, 1e300};
  double x[2] = {0.5, -3.0}, f[3], c;
  char buf[512];
  sc_prog_constant(p, &c);
  for (int i = 0; i < 4; i++) {
    sc_jet t = {{ts[i], 1.0, 0.0}}, xj[2] = {{{x[0], 0.0, 0.0}}, {{x[1], 1.0, 0.5}}}, out;
    sc_prog_value(p, ts[i], x, f);
    sc_prog_jet(p, &t, xj, &out);
    if (!sc_prog_nvars(p)) sc_prog_time(p, ts[i], f);
    sc_prog_explain(p, &t, xj, 2, buf, sizeof buf);
    x[0] = -x[0] * 3.0;
  }
  sc_prog_free(p);
  return 0;
}
