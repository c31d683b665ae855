/* The scene's inputs: section (docs/control.md): the model speeds that receive an input
 * generalized force (a joint torque or force), in order, as a list of speed names:
 *
 *     inputs: [front_frame.angle_dot, rear_frame.wx]
 *
 * The same list is the linearizer's default inputs (the columns of B, when the linearize:
 * section has no inputs: of its own), so that a gain computed from the linearization applies
 * to a simulation's inputs one for one. A motor's set-point is an input too, named
 * MOTOR.setpoint (the motor's rate, angle or position, which must be a number: its value until
 * a controller changes it). Checked at load (each name a speed of the model,
 * none twice, "did you mean"); ap_scene_add_inputs declares them on a simulation, with the
 * values 0 until a controller or ap_sim_set_input changes them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/control.h"
#include "model/setpoint.h"
#include "scene/scene_int.h"

int sc_inputs_check(sc_ctx *c, const sc_scene *s, const ap_model *m) {
  const sc_node *n = sc_map_get(s->root, "inputs");
  if (!n) return AP_OK;
  if (n->kind != SC_SEQ)
    return sc_err(c, n, "inputs: expected a list of speed names ([joint.speed, ...])");
  const char **speeds = calloc((size_t)ap_model_k(m) + 1, sizeof *speeds);
  if (!speeds) return sc_nomem(c);
  for (int i = 0; i < ap_model_k(m); i++) speeds[i] = ap_model_speed_name(m, i);
  int rc = AP_OK;
  for (int i = 0; rc == AP_OK && i < n->n; i++) {
    const sc_node *e = n->kids[i];
    int found = 0;
    for (int j = 0; e->kind == SC_SCALAR && j < ap_model_k(m); j++) found |= !strcmp(speeds[j], e->text);
    found |= e->kind == SC_SCALAR && ap_act_find_setpoint(m, e->text) >= 0;
    if (e->kind != SC_SCALAR) rc = sc_err(c, e, "expected a speed name");
    else if (!found) {
      const char *near = ap_suggest(e->text, speeds, ap_model_k(m));
      rc = sc_err(c, e, "'%s' is not a speed of the model%s%s%s: an input is a generalized "
                  "force on a speed, or MOTOR.setpoint of a motor whose set-point is a number",
                  e->text, near ? " (did you mean '" : "", near ? near : "",
                  near ? "'?)" : "");
    }
    for (int j = 0; rc == AP_OK && j < i; j++)
      if (n->kids[j]->kind == SC_SCALAR && !strcmp(n->kids[j]->text, e->text))
        rc = sc_err(c, e, "'%s' is listed twice", e->text);
  }
  free(speeds);
  return rc;
}

/* The names of the section (pointing into the tree), NULL-terminated; *count of them; NULL
 * when there is no section (or out of memory: *count = -1). */
const char **sc_input_names(const sc_scene *s, int *count) {
  const sc_node *n = s ? sc_map_get(s->root, "inputs") : NULL;
  *count = 0;
  if (!n || n->kind != SC_SEQ) return NULL;
  const char **names = calloc((size_t)n->n + 1, sizeof *names);
  if (!names) return *count = -1, NULL;
  for (int i = 0; i < n->n; i++) names[i] = n->kids[i]->text;
  *count = n->n;
  return names;
}

int ap_scene_add_inputs(const ap_scene *sc, ap_sim *sim, char *msg, size_t msg_len) {
  const sc_scene *s = sc ? sc_scene_parsed(sc) : NULL;
  if (!s || !sim || ap_sim_data(sim)->n != ap_model_n(ap_scene_model(sc)) ||
      ap_sim_data(sim)->k != ap_model_k(ap_scene_model(sc))) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_scene_add_inputs: %s",
                                 !s || !sim ? "NULL argument" : "a simulation of another model");
    return AP_ERR_ARG;
  }
  int count = 0;
  const char **names = sc_input_names(s, &count);
  if (count < 0) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s: out of memory", s->file);
    return AP_ERR_NOMEM;
  }
  int rc = names ? ap_sim_declare_inputs(sim, names) : AP_OK;
  free(names);
  if (rc != AP_OK && msg && msg_len) snprintf(msg, msg_len, "%s", ap_sim_message(sim));
  return rc;
}
