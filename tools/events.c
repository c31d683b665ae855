/* appell run: the events of a run on stderr (docs/scenes.md "Events"): one line per recorded
 * event, at most CLI_EVENT_LINES of them, then a count of the rest. */
#include <stdio.h>

#include <appell/appell.h>

#include "cli.h"

#define CLI_EVENT_LINES 20

void cli_print_events(const ap_sim *sim) {
  int n = ap_sim_event_count(sim);
  static const char *const act[] = {"stop", "log", "switch"};
  for (int i = 0; i < n && i < CLI_EVENT_LINES; i++) {
    ap_event_record r;
    if (ap_sim_event_get(sim, i, &r) != AP_OK) break;
    fprintf(stderr, "  event '%s' at t = %.12g (%s, %s)\n", r.name, r.t,
            r.direction > 0 ? "rising" : "falling", act[r.action % 3]);
  }
  if (n > CLI_EVENT_LINES)
    fprintf(stderr, "  ... and %d more events\n", n - CLI_EVENT_LINES);
}
