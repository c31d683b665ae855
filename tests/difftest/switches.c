/* Contact-mode switches for the differential tester (docs/testing.md, "Contact modes").
 *
 * A run with contact modes records its switches as events (NAME.slip, .stick, .lift_off,
 * .touchdown; appell/event.h). Two runs of one model agree when they switch in the same
 * order at times that differ within the bound derived in dt_events_compare; between the
 * switches their states are compared as any other run's (the sensitivity run switches too, so
 * the measured growth G carries the effect of a shifted switch). */
#include "switches.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void dt_events_read(dt_events *e, const ap_sim *s) {
  int n = ap_sim_event_count(s);
  for (; e->seen < n; e->seen++) {
    ap_event_record r;
    if (ap_sim_event_get(s, e->seen, &r) != AP_OK || e->n >= DT_MAXEV) continue;
    snprintf(e->name[e->n], sizeof e->name[e->n], "%s", r.name ? r.name : "?");
    e->t[e->n++] = r.t;
  }
}

/* The length of the contact's name in an event name (up to its last '.'). */
static size_t contact_len(const char *name) {
  const char *dot = strrchr(name, '.');
  return dot ? (size_t)(dot - name) : strlen(name);
}

static int same_contact(const char *a, const char *b) {
  size_t la = contact_len(a);
  return la == contact_len(b) && !strncmp(a, b, la);
}

/* The next event of e's contact `of` after index i (e->n when none before t_upto). */
static int next_of(const dt_events *e, const char *of, int i, double t_upto) {
  for (i++; i < e->n && e->t[i] <= t_upto; i++)
    if (same_contact(e->name[i], of)) return i;
  return e->n;
}

/* The time a switch's error accumulates from: the contact's previous switch t_prev, or, for a
 * switch that repeats the previous one's name (a touchdown after a bounce), the switch before
 * that chain (t0 when none). An impact does not reset the state's error, and a bounce chain's
 * flights shrink as e^i while its closing speeds do too: the i-th touchdown's time error is
 * about the gap's error over the closing speed, growing as 1 / e^i, where the time since the
 * last bounce shrinks as e^i (seed 150: errors 4.2e-7, 8.1e-7, 1.6e-6, 2.9e-6 s at touchdowns
 * 3 to 6 of one chain, e = 0.571). */
static double chain_start(const dt_events *e, int i, double t0, double t_prev) {
  for (int p = i - 1; p >= 0; p--) {
    if (!same_contact(e->name[p], e->name[i])) continue;
    if (strcmp(e->name[p], e->name[i])) return e->t[p];
    t_prev = t0;   /* a repeat: the chain's start is further back */
  }
  return t_prev;
}

/* Compare the switches of one contact (named as ref->name[first] or u->name[first]). */
static int compare_contact(const dt_events *ref, const dt_events *u, const char *of, double t0,
                           double t_upto, double tol, double *worst, char *msg, size_t len) {
  double t_prev = t0;
  for (int i = next_of(ref, of, -1, t_upto), j = next_of(u, of, -1, t_upto);
       i < ref->n || j < u->n; i = next_of(ref, of, i, t_upto), j = next_of(u, of, j, t_upto)) {
    if (i >= ref->n || j >= u->n || strcmp(ref->name[i], u->name[j])) {
      snprintf(msg, len, "'%s' at t = %.9g where the reference has '%s' at %.9g",
               j < u->n ? u->name[j] : "no switch", j < u->n ? u->t[j] : t_upto,
               i < ref->n ? ref->name[i] : "no switch", i < ref->n ? ref->t[i] : t_upto);
      return 1;
    }
    double dt = fabs(u->t[j] - ref->t[i]);
    double b = tol * (ref->t[i] - chain_start(ref, i, t0, t_prev)) + 8 * 2.3e-16 * fabs(ref->t[i]);
    *worst = fmax(*worst, dt / b);
    if (dt > b) {
      snprintf(msg, len, "'%s' at t = %.12g, the reference's at %.12g: %.3g apart, bound %.3g",
               u->name[j], u->t[j], ref->t[i], dt, b);
      return 1;
    }
    t_prev = ref->t[i];
  }
  return 0;
}

/* A burst: two switches of one contact closer than the bound of the second, which the
 * tolerance cannot resolve (two contacts on one axle sticking at once, a lift-off whose gap
 * closes again at once). The pair counts as its last switch when both have one name, else as
 * none (the contact is back in its mode). Drops them from e (a copy). */
static void drop_bursts(dt_events *e, double t0, double tol) {
  for (int i = 0; i < e->n; i++) {
    double t_prev = t0;
    for (int p = i - 1; p >= 0; p--)
      if (same_contact(e->name[p], e->name[i])) {
        t_prev = e->t[p];
        break;
      }
    int j = next_of(e, e->name[i], i, INFINITY);
    int both = j < e->n && strcmp(e->name[i], e->name[j]) != 0;
    if (j < e->n && !both) t_prev = chain_start(e, i, t0, t_prev);   /* a bounce chain */
    if (j >= e->n || e->t[j] - e->t[i] > tol * (e->t[i] - t_prev) + 8 * 2.3e-16 * e->t[j])
      continue;
    for (int k = j; both && k + 1 < e->n; k++)   /* j first: it comes after i */
      memcpy(e->name[k], e->name[k + 1], sizeof e->name[k]), e->t[k] = e->t[k + 1];
    e->n -= both;
    for (int k = i; k + 1 < e->n; k++)
      memcpy(e->name[k], e->name[k + 1], sizeof e->name[k]), e->t[k] = e->t[k + 1];
    e->n--, i = -1;   /* again from the start */
  }
}

int dt_events_compare(const dt_events *ref0, const dt_events *u0, double t0, double t_upto,
                      double tol, double *worst, char *msg, size_t len) {
  dt_events r1 = *ref0, u1 = *u0, *ref = &r1, *u = &u1;
  drop_bursts(ref, t0, tol), drop_bursts(u, t0, tol);
  *worst = 0;
  /* a switch within the bound of where a run stopped may or may not have happened in it */
  t_upto -= isfinite(t_upto) ? tol * (t_upto - t0) : 0;
  const dt_events *both[2] = {ref, u};
  for (int w = 0; w < 2; w++)
    for (int i = 0; i < both[w]->n && both[w]->t[i] <= t_upto; i++)
      if (compare_contact(ref, u, both[w]->name[i], t0, t_upto, tol, worst, msg, len))
        return 1;
  return 0;
}

/* Remove ", KEY: VALUE" (VALUE a flow mapping {...} or a scalar) everywhere in t. */
static int strip_key(char *t, const char *key) {
  int found = 0;
  for (char *p; (p = strstr(t, key));) {
    char *e = p + strlen(key);
    if (*e == '{') e = strchr(e, '}') ? strchr(e, '}') + 1 : e + strlen(e);
    else e += strcspn(e, ",}\n");
    memmove(p, e, strlen(e) + 1);
    found = 1;
  }
  return found;
}

char *dt_without_modes(const char *text) {
  char *t = malloc(strlen(text) + 1);
  if (!t) return NULL;
  strcpy(t, text);
  int any = strip_key(t, ", friction: ");
  any |= strip_key(t, ", unilateral: ");
  any |= strip_key(t, ", restitution: ");
  if (!any) free(t), t = NULL;
  return t;
}
