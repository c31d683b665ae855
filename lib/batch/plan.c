/* Sweep plans (include/appell/batch.h): which scene values vary and how, and the overrides
 * of run i.
 *
 * Layout: parameters in one array, grids first (in the order added), then random ones. Run
 * i = g * samples + j: grid point g (the first grid varies slowest, like nested loops in the
 * order given) and sample j. A range A:B:N gives x_m = A + m (B - A)/(N - 1), the last one B
 * exactly (the values numpy.linspace gives). Random draws are counter-based, so that any
 * slice of a plan (a shard, a Dask chunk) draws the same numbers as the whole plan: draw d of
 * parameter r in sample j is U = mix(mix(mix(seed) ^ j) ^ (2 r + d)) / 2^64 with SplitMix64's
 * finalizer `mix` (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
 * OOPSLA 2014), U in [0, 1) with 53 bits; normals by Box-Muller,
 * x = mu + sigma sqrt(-2 ln(1 - U0)) cos(2 pi U1). Invariant: a plan that was built without
 * error gives every run's overrides without error. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/batch.h"
#include "appell/scene.h"
#include "batch/batch_int.h"

#define PLAN_MAX_PARAMS 64
#define PLAN_MAX_POINTS 1000000000L

enum { PL_RANGE, PL_LIST, PL_NORMAL, PL_UNIFORM };

typedef struct plan_param {
  char *path;
  int kind;
  double a, b;             /* range ends; normal mu, sigma; uniform bounds */
  long n;                  /* grid size (range, list) */
  char **words;            /* list: each value as written (n) */
  double *x;               /* list: each value's number, NaN for words (n) */
} plan_param;

struct ap_plan {
  plan_param par[PLAN_MAX_PARAMS];
  int npar, ngrid;
  long samples;            /* 0 until ap_plan_set_samples */
  uint64_t seed;
};

static int say(char *msg, size_t len, const char *fmt, const char *a, const char *b) {
  if (msg && len) snprintf(msg, len, fmt, a, b);
  return AP_ERR_ARG;
}

int ap_plan_create(ap_plan **out) {
  if (!out) return AP_ERR_ARG;
  *out = calloc(1, sizeof **out);
  return *out ? AP_OK : AP_ERR_NOMEM;
}

static void param_free(plan_param *q) {
  for (long m = 0; q->words && m < q->n; m++) free(q->words[m]);
  free(q->words);
  free(q->x);
  free(q->path);
  memset(q, 0, sizeof *q);
}

void ap_plan_free(ap_plan *p) {
  if (!p) return;
  for (int r = 0; r < p->npar; r++) param_free(&p->par[r]);
  free(p);
}

static char *dup_n(const char *s, size_t n) {
  char *d = malloc(n + 1);
  if (d) memcpy(d, s, n), d[n] = '\0';
  return d;
}

/* s without surrounding blanks, copied. */
static char *trimmed(const char *s, size_t n) {
  while (n && isspace((unsigned char)*s)) s++, n--;
  while (n && isspace((unsigned char)s[n - 1])) n--;
  return dup_n(s, n);
}

/* Split "PATH=REST": the path (no blanks, no '=') into q->path; *rest after the '='. */
static int split_spec(const char *spec, plan_param *q, const char **rest, char *msg, size_t len) {
  const char *eq = spec ? strchr(spec, '=') : NULL;
  if (!eq || eq == spec) return say(msg, len, "'%s': expected PATH=VALUES", spec ? spec : "", "");
  for (const char *c = spec; c < eq; c++)
    if (isspace((unsigned char)*c)) return say(msg, len, "'%s': blank in the path", spec, "");
  q->path = dup_n(spec, (size_t)(eq - spec));
  *rest = eq + 1;
  return q->path ? AP_OK : AP_ERR_NOMEM;
}

/* A constant expression in text[0..n). */
static int number(const char *spec, const char *text, size_t n, double *x, char *msg,
                  size_t len) {
  char *t = trimmed(text, n), why[512];
  if (!t) return AP_ERR_NOMEM;
  int rc = ap_scene_constant(t, x, why, sizeof why);
  if (rc != AP_OK && msg && len) snprintf(msg, len, "'%s': '%s': %s", spec, t, why);
  free(t);
  return rc;
}

static int parse_range(const char *spec, const char *rest, plan_param *q, char *msg,
                       size_t len) {
  const char *c1 = strchr(rest, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
  if (!c2 || strchr(c2 + 1, ':'))
    return say(msg, len, "'%s': expected PATH=A:B:N (from A to B in N values)", spec, "");
  int rc = number(spec, rest, (size_t)(c1 - rest), &q->a, msg, len);
  if (rc == AP_OK) rc = number(spec, c1 + 1, (size_t)(c2 - c1 - 1), &q->b, msg, len);
  if (rc != AP_OK) return rc;
  if (!isfinite(q->b - q->a)) {
    if (msg && len) snprintf(msg, len, "'%s': B - A = %g - (%g) overflows: the values would not "
                             "be finite", spec, q->b, q->a);
    return AP_ERR_ARG;
  }
  char *end = NULL;
  long n = strtol(c2 + 1, &end, 10);
  while (end && isspace((unsigned char)*end)) end++;
  if (end == c2 + 1 || *end || n < 1 || n > PLAN_MAX_POINTS)
    return say(msg, len, "'%s': N must be a whole number from 1 to 10^9, got '%s'", spec, c2 + 1);
  q->kind = PL_RANGE, q->n = n;
  return AP_OK;
}

/* A word (verner6, dae): letters, digits, '_', '-', '.', starting with a letter. */
static int is_word(const char *s) {
  if (!isalpha((unsigned char)s[0])) return 0;
  for (; *s; s++)
    if (!isalnum((unsigned char)*s) && !strchr("_-.", *s)) return 0;
  return 1;
}

static int parse_list(const char *spec, const char *rest, plan_param *q, char *msg,
                      size_t len) {
  long n = 1;
  for (const char *c = rest; *c; c++) n += *c == ',';
  q->kind = PL_LIST;
  q->words = calloc((size_t)n, sizeof *q->words);
  q->x = calloc((size_t)n, sizeof *q->x);
  if (!q->words || !q->x) return AP_ERR_NOMEM;
  const char *s = rest;
  for (long m = 0; m < n; m++) {
    size_t k = strcspn(s, ",");
    char *w = trimmed(s, k), why[512];
    if (!w) return AP_ERR_NOMEM;
    q->words[q->n++] = w;
    if (!w[0]) return say(msg, len, "'%s': an empty value in the list", spec, "");
    if (ap_scene_constant(w, &q->x[m], why, sizeof why) != AP_OK) {
      if (!is_word(w)) {
        if (msg && len) snprintf(msg, len, "'%s': '%s': %s", spec, w, why);
        return AP_ERR_ARG;
      }
      q->x[m] = NAN;
    }
    s += k + (s[k] == ',');
  }
  return AP_OK;
}

/* Insert a new parameter: grids before the random ones. */
static plan_param *new_param(ap_plan *p, int grid, char *msg, size_t len) {
  if (p->npar >= PLAN_MAX_PARAMS) {
    say(msg, len, "at most 64 parameters in a plan%s%s", "", "");
    return NULL;
  }
  int at = grid ? p->ngrid : p->npar;
  memmove(&p->par[at + 1], &p->par[at], sizeof p->par[0] * (size_t)(p->npar - at));
  memset(&p->par[at], 0, sizeof p->par[0]);
  p->npar++, p->ngrid += grid;
  return &p->par[at];
}

/* Remove the parameter q again after a parse error. */
static void drop_param(ap_plan *p, plan_param *q, int grid) {
  int at = (int)(q - p->par);
  param_free(q);
  memmove(&p->par[at], &p->par[at + 1], sizeof p->par[0] * (size_t)(p->npar - at - 1));
  p->npar--, p->ngrid -= grid;
}

/* A path may vary once: a second grid or random value for it would override the first in
 * every run while the table still listed the first's values as used. */
static int unique_path(const ap_plan *p, const plan_param *q, char *msg, size_t len) {
  for (int i = 0; i < p->npar; i++)
    if (&p->par[i] != q && p->par[i].path && strcmp(p->par[i].path, q->path) == 0)
      return say(msg, len, "'%s' is varied twice (one --grid or --random per path)%s", q->path,
                 "");
  return AP_OK;
}

/* A failed allocation says so (the parsers leave msg alone then). */
static int nomem_said(int rc, const char *spec, char *msg, size_t len) {
  if (rc == AP_ERR_NOMEM) say(msg, len, "'%s': out of memory%s", spec, "");
  return rc;
}

int ap_plan_add_grid(ap_plan *p, const char *spec, char *msg, size_t len) {
  if (!p || !spec) return say(msg, len, "NULL argument%s%s", "", "");
  plan_param *q = new_param(p, 1, msg, len);
  if (!q) return AP_ERR_ARG;
  const char *rest = NULL;
  int rc = split_spec(spec, q, &rest, msg, len);
  if (rc == AP_OK) rc = unique_path(p, q, msg, len);
  if (rc == AP_OK) rc = strchr(rest, ':') ? parse_range(spec, rest, q, msg, len)
                                          : parse_list(spec, rest, q, msg, len);
  if (rc == AP_OK && ap_plan_count(p) < 0)
    rc = say(msg, len, "'%s': the plan would have more than 2^53 runs%s", spec, "");
  if (rc != AP_OK) drop_param(p, q, 1);
  return nomem_said(rc, spec, msg, len);
}

/* "name(ARG1,ARG2)": two constant expressions (commas inside parentheses do not split). */
static int parse_call(const char *spec, const char *rest, const char *name, double *a,
                      double *b, char *msg, size_t len) {
  size_t ln = strlen(name), n = strlen(rest);
  if (strncmp(rest, name, ln) != 0 || rest[ln] != '(' || n < ln + 2 || rest[n - 1] != ')')
    return 1;
  const char *in = rest + ln + 1, *end = rest + n - 1, *comma = NULL;
  int depth = 0;
  for (const char *c = in; c < end; c++) {
    depth += (*c == '(') - (*c == ')');
    if (*c == ',' && depth == 0) {
      if (comma) return say(msg, len, "'%s': %s takes two arguments", spec, name);
      comma = c;
    }
  }
  if (!comma) return say(msg, len, "'%s': %s takes two arguments", spec, name);
  int rc = number(spec, in, (size_t)(comma - in), a, msg, len);
  return rc == AP_OK ? number(spec, comma + 1, (size_t)(end - comma - 1), b, msg, len) : rc;
}

int ap_plan_add_random(ap_plan *p, const char *spec, char *msg, size_t len) {
  if (!p || !spec) return say(msg, len, "NULL argument%s%s", "", "");
  plan_param *q = new_param(p, 0, msg, len);
  if (!q) return AP_ERR_ARG;
  const char *rest = NULL;
  int rc = split_spec(spec, q, &rest, msg, len);
  if (rc == AP_OK) rc = unique_path(p, q, msg, len);
  if (rc == AP_OK) {
    while (isspace((unsigned char)*rest)) rest++;
    q->kind = PL_NORMAL;
    rc = parse_call(spec, rest, "normal", &q->a, &q->b, msg, len);
    if (rc == 1) q->kind = PL_UNIFORM, rc = parse_call(spec, rest, "uniform", &q->a, &q->b, msg, len);
    if (rc == 1)
      rc = say(msg, len, "'%s': expected PATH=normal(MU,SIGMA) or PATH=uniform(A,B)", spec, "");
  }
  if (rc == AP_OK && q->kind == PL_NORMAL && !(q->b >= 0))
    rc = say(msg, len, "'%s': the standard deviation must not be negative%s", spec, "");
  if (rc == AP_OK && q->kind == PL_UNIFORM && !(q->a <= q->b))
    rc = say(msg, len, "'%s': uniform(A,B) needs A <= B%s", spec, "");
  if (rc != AP_OK) drop_param(p, q, 0);
  return nomem_said(rc, spec, msg, len);
}

int ap_plan_set_samples(ap_plan *p, long samples, uint64_t seed) {
  if (!p || samples < 1 || samples > PLAN_MAX_POINTS) return AP_ERR_ARG;
  p->samples = samples, p->seed = seed;
  return ap_plan_count(p) < 0 ? (p->samples = 0, AP_ERR_ARG) : AP_OK;
}

long ap_plan_count(const ap_plan *p) {
  if (!p) return 0;
  double total = p->samples > 0 ? (double)p->samples : 1.0;
  for (int r = 0; r < p->ngrid; r++) total *= (double)p->par[r].n;
  return total > 9007199254740992.0 ? -1 : (long)total;
}

int ap_plan_nparams(const ap_plan *p) { return p ? p->npar : 0; }

const char *ap_plan_path(const ap_plan *p, int r) {
  return p && r >= 0 && r < p->npar ? p->par[r].path : NULL;
}

static uint64_t mix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static double uniform01(uint64_t seed, long j, int r, int d) {
  uint64_t z = mix(mix(mix(seed) ^ (uint64_t)j) ^ (uint64_t)(2 * r + d));
  return (double)(z >> 11) * 0x1.0p-53;
}

/* Parameter r's number in run i (NaN for a word); *word = its text for list values. */
static double param_value(const ap_plan *p, long i, int r, const char **word) {
  const plan_param *q = &p->par[r];
  long samples = p->samples > 0 ? p->samples : 1, g = i / samples, j = i % samples;
  *word = NULL;
  if (r < p->ngrid) {
    long stride = 1;
    for (int s = r + 1; s < p->ngrid; s++) stride *= p->par[s].n;
    long m = (g / stride) % q->n;
    if (q->kind == PL_LIST) return *word = isnan(q->x[m]) ? q->words[m] : NULL, q->x[m];
    if (q->n == 1) return q->a;
    return m == q->n - 1 ? q->b : q->a + (double)m * ((q->b - q->a) / (double)(q->n - 1));
  }
  double u0 = uniform01(p->seed, j, r, 0);
  if (q->kind == PL_UNIFORM) return q->a + (q->b - q->a) * u0;
  double u1 = uniform01(p->seed, j, r, 1);
  return q->a + q->b * sqrt(-2.0 * log(1.0 - u0)) * cos(6.28318530717958647692 * u1);
}

static int write_set(const plan_param *q, const char *word, double x, char *buf, size_t len) {
  int w = word ? snprintf(buf, len, "%s=%s", q->path, word)
               : snprintf(buf, len, "%s=%.17g", q->path, x);
  return w >= 0 && (size_t)w < len ? AP_OK : AP_ERR_ARG;
}

int ap_plan_value(const ap_plan *p, long i, int r, double *x, char *buf, size_t len) {
  if (!p || r < 0 || r >= p->npar || i < 0 || i >= ap_plan_count(p)) return AP_ERR_ARG;
  if (r >= p->ngrid && p->samples <= 0) return AP_ERR_ARG;
  const char *word = NULL;
  double v = param_value(p, i, r, &word);
  if (x) *x = v;
  return buf ? write_set(&p->par[r], word, v, buf, len) : AP_OK;
}

int ap_plan_typical(const ap_plan *p, int r, char *buf, size_t len) {
  if (!p || r < 0 || r >= p->npar || !buf) return AP_ERR_ARG;
  const plan_param *q = &p->par[r];
  switch (q->kind) {
    case PL_LIST: return write_set(q, isnan(q->x[0]) ? q->words[0] : NULL, q->x[0], buf, len);
    case PL_RANGE:
    case PL_NORMAL: return write_set(q, NULL, q->a, buf, len);
    default: return write_set(q, NULL, 0.5 * (q->a + q->b), buf, len);
  }
}

/* The plan's part of a sweep's identity (identity.c): every parameter's path, kind and values
 * as numbers (lists: each number, or each word), the samples and the seed; not the text the
 * plan was written in, so 1:2:3 and 1.0:2:3 are the same plan. */
uint64_t ap_bat_plan_hash(const ap_plan *p, uint64_t h) {
  long counts[2] = {p->npar, p->samples};
  h = ap_bat_hash(h, counts, sizeof counts);
  h = ap_bat_hash(h, &p->seed, sizeof p->seed);
  for (int r = 0; r < p->npar; r++) {
    const plan_param *q = &p->par[r];
    h = ap_bat_hash(h, q->path, strlen(q->path) + 1);
    h = ap_bat_hash(h, &q->kind, sizeof q->kind);
    h = ap_bat_hash(h, &q->n, sizeof q->n);
    if (q->kind != PL_LIST) {
      double ab[2] = {q->a + 0.0, q->b + 0.0};   /* -0 as 0 */
      h = ap_bat_hash(h, ab, sizeof ab);
    }
    for (long m = 0; q->kind == PL_LIST && m < q->n; m++)
      h = isnan(q->x[m]) ? ap_bat_hash(h, q->words[m], strlen(q->words[m]) + 1)
                         : ap_bat_hash(h, &q->x[m], sizeof q->x[m]);
  }
  return h;
}
