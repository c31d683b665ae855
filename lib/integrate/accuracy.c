/* How tight a tolerance each method delivers (ap_method_info.rtol_floor).
 *
 * Measured by bench/plot/accuracy.py on the reference problems with closed forms (knife edge on
 * an incline, Chaplygin sleigh, ball on a turntable at constant and at varying Omega, bead on
 * a rotating line; minimal mode, rtol = atol): the global position error in units of
 * rtol x the position scale stays below 10 for the explicit pairs of order 5 and more (below
 * 50 for bs3) at every rtol from 1e-6 to 1e-12, while CVODE's multistep methods drift away
 * from it as rtol tightens: adams 160 x at 1e-8, 250 x at 1e-10, 1200 x at 1e-12; bdf 160 x at
 * 1e-8, 1800 x at 1e-10, 4500 x at 1e-12 (with its Newton convergence coefficient 0.003,
 * stepper_cvode.c; docs/steppers.md "Accuracy"). The floor is the
 * smallest rtol at which a method's worst error stayed within 200 x rtol; 0 means no floor was
 * found down to 1e-12. */
#include <string.h>

#include "integrate/stepper.h"

double ap_step_rtol_floor(const char *name) {
  static const struct {
    const char *name;
    double floor;
  } floors[] = {{"adams", 1e-8}, {"bdf", 1e-8}};
  for (size_t i = 0; name && i < sizeof floors / sizeof floors[0]; i++)
    if (strcmp(floors[i].name, name) == 0) return floors[i].floor;
  return 0.0;
}
