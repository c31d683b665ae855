/* The differential tester's contact-mode switches (docs/testing.md, "Contact modes"): the
 * events a run recorded, and their comparison with the reference's. */
#ifndef AP_DIFFTEST_SWITCHES_H
#define AP_DIFFTEST_SWITCHES_H

#include "appell/appell.h"

#define DT_MAXEV 32

typedef struct dt_events {
  int n;                   /* events recorded (the first DT_MAXEV kept) */
  int seen;                /* ap_sim_event_count already read */
  char name[DT_MAXEV][48];
  double t[DT_MAXEV];
} dt_events;

/* Append the events s recorded since the last call. */
void dt_events_read(dt_events *e, const ap_sim *s);

/* Compare a run's switches with the reference's up to time t_upto (less its bound where a
 * run stopped), contact by contact (contacts switching at nearly one time may come in either
 * order): the same names in the same order, each time within tol (t_i - t_{i-1}) of the
 * reference's, t_{i-1} the contact's previous switch (t0 for its first): a smooth event
 * function's error after s steps is s rtol of its scale, and it crosses 0 at a rate of its
 * scale over the time since the contact's last switch. Two switches of one contact closer
 * than that bound count as the last one (same names) or as none (a lift-off and a touchdown,
 * a slip and a stick). Writes the first difference to msg and
 * returns 1, or returns 0 with *worst the largest |dt| / bound. */
int dt_events_compare(const dt_events *ref, const dt_events *u, double t0, double t_upto,
                      double tol, double *worst, char *msg, size_t len);

/* The scene text without its contact modes (friction, unilateral, restitution keys of its
 * rolling constraints), malloc'd; NULL when it has none. */
char *dt_without_modes(const char *text);

#endif
