/* The warning of appell run when a method is asked for a tolerance it does not deliver: below
 * its ap_method_info.rtol_floor (measured on the reference problems, docs/steppers.md
 * "Accuracy") the global error grows past 200 x rtol; the warning names the floor and the
 * methods that keep their error near rtol. */
#include <stdio.h>

#include <appell/appell.h>

#include "cli.h"

void cli_warn_tolerance(const char *cmd, int dae, const char *method, double rtol) {
  ap_method_info mi;
  if (dae || ap_method_find(method, &mi) != AP_OK) return;
  if (!(mi.rtol_floor > 0) || !(rtol < mi.rtol_floor)) return;
  fprintf(stderr, "appell %s: warning: method %s at rtol = %g: below rtol %g its global error "
          "on the reference problems grew past 200 x rtol (3300 x at 1e-12 for bdf, 1200 x for "
          "adams; docs/steppers.md, Accuracy): for tight tolerances use dop853, fehlberg8, "
          "verner6 or dopri5, whose error stays within 10 x rtol\n", cmd, mi.name,
          rtol, mi.rtol_floor);
}
