/* Body quantities in scene expressions (docs/scenes.md "Expressions of the state"): the names
 * BODY.x, .y, .z, .vx, .vy, .vz, .roll, .pitch, .yaw, .heading, .tilt, .spin, .wx, .wy, .wz
 * of every body, and reading them at a state.
 *
 * The names extend the state names table (state.c): entry i reads refs[i] = {body,
 * AP_STATE_BODY, quantity} (include/appell/body.h, ap_body_qty, where the angles' conventions
 * are). A name the table already has (a joint coordinate or speed lent under its child body's
 * name, e.g. the plane-contact joint's `disk.x`) keeps its meaning: with the joint frames at
 * the body origin it is the same quantity. The model evaluates a body quantity from its own
 * kinematics, so its exact partials reach the linearizer through the complex-step build;
 * scene code that evaluates an expression outside the model (events, outputs, the checks at
 * the initial state) reads it with ap_body_quantity after the kinematics at that state. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static const char *const qty_names[AP_BODY_QTY_COUNT] = {
    "x", "y", "z", "vx", "vy", "vz", "roll", "pitch", "yaw", "heading", "tilt", "spin",
    "wx", "wy", "wz"};

static int has(const sc_state_names *t, const char *name) {
  for (int i = 0; i < t->count; i++)
    if (strcmp(t->names[i], name) == 0) return 1;
  return 0;
}

int sc_state_names_add_bodies(const sc_scene *s, sc_state_names *t) {
  for (int b = 0; b < s->nb; b++)
    for (int q = 0; q < AP_BODY_QTY_COUNT; q++) {
      size_t len = strlen(s->bodies[b].name) + strlen(qty_names[q]) + 2;
      char *name = malloc(len);
      if (!name) return AP_ERR_NOMEM;
      snprintf(name, len, "%s.%s", s->bodies[b].name, qty_names[q]);
      if (has(t, name)) {
        free(name);
        continue;
      }
      t->names[t->count] = name;
      t->refs[t->count] = (ap_state_input){b, AP_STATE_BODY, q};
      t->driven[t->count++] = 0;
    }
  return AP_OK;
}

int sc_inputs_read_bodies(const ap_state_input *in, int nin) {
  for (int i = 0; i < nin; i++)
    if (in[i].speed == AP_STATE_BODY) return 1;
  return 0;
}

int sc_state_gather(const ap_model *m, const ap_data *d, const ap_state_input *in,
                    const int *index, int nin, const double *q, const double *v, double *x) {
  for (int i = 0; i < nin; i++) {
    if (in[i].speed != AP_STATE_BODY) {
      x[i] = in[i].speed ? v[index[i]] : q[index[i]];
      continue;
    }
    int rc = ap_body_quantity(m, d, in[i].joint, in[i].index, &x[i]);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

int sc_state_at(const ap_model *m, ap_data *d, double t, const double *q, const double *v) {
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)ap_model_n(m));
  memcpy(d->v, v, sizeof(double) * (size_t)ap_model_k(m));
  return ap_body_eval(m, d);
}
