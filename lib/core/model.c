/* The compiled model of a math-level system.
 *
 * ap_model_from_system validates a definition once (sizes, required callbacks, the bias
 * source) and keeps a private copy with names filled in, so the hot loop can trust it.
 * Invariant: a model is never modified after it is returned. */
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "core/defcheck.h"
#include "core/sizes.h"
#include "core/text.h"

ap_system_def ap_system_def_default(void) {
  ap_system_def def;
  memset(&def, 0, sizeof def);
  def.name = "system";
  def.bias_source = AP_BIAS_CALLBACK;
  def.internal_check = AP_DEF_CHECK;
  return def;
}

static int fail(char *msg, size_t len, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int fail(char *msg, size_t len, const char *fmt, ...) {
  if (msg && len > 0) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, len, fmt, ap);
    va_end(ap);
  }
  return AP_ERR_ARG;
}

/* A copy of count names, or "<prefix><i>" where none are given. NULL on allocation failure. */
static char **copy_names(const char *const *names, int count, const char *prefix) {
  char **out = calloc((size_t)(count > 0 ? count : 1), sizeof *out);
  if (!out) return NULL;
  for (int i = 0; i < count; i++) {
    char buf[32];
    const char *s = names && names[i] ? names[i] : NULL;
    if (!s) {
      snprintf(buf, sizeof buf, "%s%d", prefix, i);
      s = buf;
    }
    out[i] = malloc(strlen(s) + 1);
    if (!out[i]) return out;   /* caller frees; detects the NULL */
    strcpy(out[i], s);
  }
  return out;
}

static void free_names(char **names, int count) {
  if (!names) return;
  for (int i = 0; i < count; i++) free(names[i]);
  free(names);
}

int ap_core_check_sizes(const char *model, int n, int k, int b, int christoffel, char *msg,
                        size_t len) {
  const double lim = (double)INT_MAX, dn = n, dk = k, db = b;
  const char *what = NULL;
  double entries = 0;
  if (dk * dk > lim) what = "k x k matrices (g, B, G)", entries = dk * dk;
  else if (dn * dk > lim) what = "n x k matrix N", entries = dn * dk;
  else if (db * (dk + 1) > lim) what = "b x (k + 1) matrix [A a0]", entries = db * (dk + 1);
  else if (christoffel && dn * dk * dk > lim) what = "n x k x k array dg/dq", entries = dn * dk * dk;
  if (!what) return AP_OK;
  return fail(msg, len, "model '%s' (n = %d, k = %d, b = %d): its %s would have %.0f entries, "
              "more than the %d a 32-bit LAPACK integer indexes (at most %d speeds on the dense "
              "path)", model, n, k, b, what, entries, INT_MAX, 46340);
}

static int validate(const ap_system_def *d, char *msg, size_t len) {
  const char *nm = d->name ? d->name : "system";
  if (d->internal_check != AP_DEF_CHECK)
    return fail(msg, len, "ap_system_def '%s' " AP_DEF_NOT_DEFAULT("ap_system_def"), nm);
  if (d->n < 1 || d->k < 1 || d->b < 0)
    return fail(msg, len, "system '%s': sizes n = %d, k = %d, b = %d (need n >= 1, k >= 1, "
                "b >= 0)", nm, d->n, d->k, d->b);
  if (d->n > AP_MAX_SIZE || d->k > AP_MAX_SIZE || d->b > AP_MAX_SIZE)
    return fail(msg, len, "system '%s': sizes n = %d, k = %d, b = %d (at most %d each)", nm,
                d->n, d->k, d->b, AP_MAX_SIZE);
  int rc = ap_core_check_sizes(nm, d->n, d->k, d->b, d->bias_source == AP_BIAS_CHRISTOFFEL,
                               msg, len);
  if (rc != AP_OK) return rc;
  if (!d->kinematic && d->n != d->k)
    return fail(msg, len, "system '%s': n = %d coordinates but k = %d speeds and no kinematic "
                "callback N(q): with N = I they must be equal", nm, d->n, d->k);
  if (!d->metric) return fail(msg, len, "system '%s': the metric callback g is required", nm);
  if (d->b > 0 && (!d->constraint || !d->gamma))
    return fail(msg, len, "system '%s': b = %d constraint rows need both the constraint "
                "(A, a0) and the gamma callbacks", nm, d->b);
  switch (d->bias_source) {
    case AP_BIAS_CALLBACK:
      if (!d->bias)
        return fail(msg, len, "system '%s': bias_source is AP_BIAS_CALLBACK but no bias "
                    "callback h is given (use AP_BIAS_CHRISTOFFEL with metric_deriv, or "
                    "AP_BIAS_ZERO for a constant metric)", nm);
      break;
    case AP_BIAS_CHRISTOFFEL:
      if (!d->metric_deriv)
        return fail(msg, len, "system '%s': AP_BIAS_CHRISTOFFEL needs the metric_deriv "
                    "callback dg/dq", nm);
      if (d->kinematic)
        return fail(msg, len, "system '%s': AP_BIAS_CHRISTOFFEL needs v = q' (no kinematic "
                    "callback); give a bias callback for quasi-velocities", nm);
      break;
    case AP_BIAS_ZERO: break;
    default:
      return fail(msg, len, "system '%s': unknown bias_source %d", nm, (int)d->bias_source);
  }
  return AP_OK;
}

int ap_model_from_system(const ap_system_def *def, ap_model **out, char *msg, size_t msg_len) {
  if (!out) return fail(msg, msg_len, "ap_model_from_system: out is NULL");
  *out = NULL;
  if (!def) return fail(msg, msg_len, "ap_model_from_system: def is NULL");
  int rc = validate(def, msg, msg_len);
  if (rc != AP_OK) return rc;
  ap_model *m = calloc(1, sizeof *m);
  if (!m) return AP_ERR_NOMEM;
  m->sys = *def;
  m->lscale = 1.0;   /* a math-level system has no lengths of its own (core.h) */
  m->n = def->n;
  m->k = def->k;
  m->b = def->b;
  ap_core_copy_name(m->name, sizeof m->name, def->name ? def->name : "system");   /* "..." if cut */
  m->coord_names = copy_names(def->coord_names, m->n, "q");
  m->speed_names = copy_names(def->speed_names, m->k, "v");
  m->constraint_names = copy_names(def->constraint_names, m->b, "row");
  int ok = m->coord_names && m->speed_names && m->constraint_names;
  for (int i = 0; ok && i < m->n; i++) ok = m->coord_names[i] != NULL;
  for (int i = 0; ok && i < m->k; i++) ok = m->speed_names[i] != NULL;
  for (int i = 0; ok && i < m->b; i++) ok = m->constraint_names[i] != NULL;
  if (!ok) {
    ap_model_free(m);
    return AP_ERR_NOMEM;
  }
  m->sys.name = m->name;
  m->sys.coord_names = (const char *const *)m->coord_names;
  m->sys.speed_names = (const char *const *)m->speed_names;
  m->sys.constraint_names = (const char *const *)m->constraint_names;
  *out = m;
  return AP_OK;
}

void ap_model_free(ap_model *m) {
  if (!m) return;
  if (m->ops_destroy) m->ops_destroy(m->ops_impl);
  if (m->ev.destroy) m->ev.destroy(m->ev.impl);
  free_names(m->coord_names, m->n);
  free_names(m->speed_names, m->k);
  free_names(m->constraint_names, m->b);
  free(m->vscale);
  free(m);
}

int ap_model_path(const ap_model *m) {
  return m ? (m->ops ? AP_PATH_TREE : AP_PATH_DENSE) : AP_ERR_ARG;
}

int ap_model_n(const ap_model *m) { return m ? m->n : AP_ERR_ARG; }
int ap_model_k(const ap_model *m) { return m ? m->k : AP_ERR_ARG; }
int ap_model_b(const ap_model *m) { return m ? m->b : AP_ERR_ARG; }
const char *ap_model_name(const ap_model *m) { return m ? m->name : "?"; }

const char *ap_model_coord_name(const ap_model *m, int i) {
  return m && i >= 0 && i < m->n ? m->coord_names[i] : "?";
}
const char *ap_model_speed_name(const ap_model *m, int i) {
  return m && i >= 0 && i < m->k ? m->speed_names[i] : "?";
}
const char *ap_model_constraint_name(const ap_model *m, int s) {
  return m && s >= 0 && s < m->b ? m->constraint_names[s] : "?";
}

int ap_core_has_cs(const ap_model *m, char *msg, size_t len) {
  if (!m->ev.position_cs) {
    snprintf(msg, len, "model '%s' is a math-level system: its callbacks are C functions of "
             "doubles", m->name);
    return 0;
  }
  return !m->ev.cs_blocker || m->ev.cs_blocker(m, msg, len) == 0;
}
