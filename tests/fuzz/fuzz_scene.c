/* libFuzzer harness: the scene loader (docs/scenes.md). The input is a scene file's text.
 *
 * ap_scene_load_string, and when it loads: the initial state, every expression at t0 and at
 * a later time, an output row, and a short simulation in the scene's own mode (at most 200
 * steps, to t0 + 2 output intervals). Any status is fine; a crash, a sanitizer report, a
 * leak or a hang is a finding. Seeds: examples/scenes and tests/scenes (scripts/fuzz). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

static void simulate(ap_scene *sc) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double *q = calloc((size_t)(n + k) + 1, sizeof *q), *v = q ? q + n : NULL;
  double *row = calloc((size_t)ap_scene_output_count(sc) + 1, sizeof *row);
  char msg[512];
  if (q && row && ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg) == AP_OK) {
    ap_scene_run run;
    ap_scene_get_run(sc, &run);
    run.sim.max_steps = 200;
    ap_sim *s = NULL;
    ap_scene_check_time(sc, run.t0, msg, sizeof msg);
    ap_scene_check_time(sc, run.t0 + 1.0, msg, sizeof msg);
    if (ap_sim_create(m, &run.sim, run.t0, q, v, &s, msg, sizeof msg) == AP_OK) {
      ap_scene_output_row(sc, s, row);
      for (int i = 1; i <= 2; i++)
        if (ap_sim_advance(s, run.t0 + i * run.interval) != AP_OK) break;
      ap_scene_output_row(sc, s, row);
      double E = 0.0, r = 0.0;
      ap_scene_energy(sc, ap_sim_time(s), ap_sim_q(s), ap_sim_v(s), &E);
      ap_scene_residual(sc, ap_sim_time(s), ap_sim_q(s), ap_sim_v(s), &r);
    }
    ap_sim_free(s);
  }
  free(q), free(row);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  ap_scene *sc = NULL;
  char msg[1024];
  if (ap_scene_load_string((const char *)data, size, "fuzz.yaml", NULL, 0, &sc, msg,
                           sizeof msg) == AP_OK)
    simulate(sc);
  ap_scene_free(sc);
  return 0;
}
