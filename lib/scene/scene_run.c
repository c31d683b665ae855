/* Scene runs side by side: the per-run output state (ap_scene_out) and constant expressions
 * (ap_scene_constant), for programs that run one scene many times, possibly from several
 * threads at once (lib/batch, the Python package).
 *
 * An ap_scene_out owns what ap_scene_output_row keeps inside the scene: a data struct that the
 * output stages evaluate in (kinematics, energy, the position stage for the residual) and the
 * row-to-row memory of sc_out (unwrapped Euler angles, E(t0), the row count). The scene's
 * parsed tree and its model are only read, so outputs of many runs of one scene may be
 * evaluated concurrently. Invariant: an ap_scene_out's columns are the scene's columns. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

struct ap_scene_out {
  const ap_scene *sc;
  sc_out out;
  ap_data *d;              /* scratch for outputs and energy; this run's only */
};

int ap_scene_out_create(const ap_scene *s, ap_scene_out **out) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  if (!s) return AP_ERR_ARG;
  ap_scene_out *o = calloc(1, sizeof *o);
  if (!o) return AP_ERR_NOMEM;
  o->sc = s;
  const ap_model *m = ap_scene_model(s);
  if (ap_data_create(m, &o->d) != AP_OK || sc_out_names(&o->out, sc_scene_parsed(s), m) != AP_OK) {
    ap_scene_out_free(o);
    return AP_ERR_NOMEM;
  }
  *out = o;
  return AP_OK;
}

void ap_scene_out_free(ap_scene_out *o) {
  if (!o) return;
  ap_data_free(o->d);
  sc_out_free(&o->out);
  free(o);
}

int ap_scene_out_row(ap_scene_out *o, ap_sim *sim, double *row) {
  if (!o || !sim || !row) return AP_ERR_ARG;
  const ap_data *sd = ap_sim_data(sim);   /* the simulation must be of the scene's model */
  const ap_model *m = ap_scene_model(o->sc);
  if (sd->n != ap_model_n(m) || sd->k != ap_model_k(m) || sd->b != ap_model_b(m))
    return AP_ERR_ARG;
  return sc_out_row(&o->out, sc_scene_parsed(o->sc), ap_scene_model(o->sc), o->d, sim, row);
}

int ap_scene_out_energy(ap_scene_out *o, double t, const double *q, const double *v,
                        double *E) {
  if (!o || !q || !v || !E) return AP_ERR_ARG;
  const ap_model *m = ap_scene_model(o->sc);
  o->d->t = t;
  memcpy(o->d->q, q, sizeof(double) * (size_t)ap_model_n(m));
  memcpy(o->d->v, v, sizeof(double) * (size_t)ap_model_k(m));
  double T = 0.0, V = 0.0;
  int rc = sc_out_energy(m, o->d, &T, &V);
  *E = T + V;
  return rc;
}

int ap_scene_constant(const char *text, double *x, char *msg, size_t msg_len) {
  if (msg && msg_len) msg[0] = '\0';
  if (!text || !x) {
    if (msg && msg_len) snprintf(msg, msg_len, "NULL argument");
    return AP_ERR_ARG;
  }
  /* A one-node tree at 1:1 with an empty key path: sc_number's messages then start with the
   * fixed prefix below, which is dropped (the caller names the text's origin). */
  sc_node n = {.kind = SC_SCALAR, .text = (char *)text, .line = 1, .col = 1, .path = ""};
  sc_ctx c = {"", "", AP_OK};
  double v = 0.0;
  int rc = sc_number(&c, &n, &v);
  if (rc != AP_OK) {
    static const char prefix[] = ":1:1: (top level): ";
    const char *what = strncmp(c.msg, prefix, sizeof prefix - 1) == 0 ? c.msg + sizeof prefix - 1
                                                                       : c.msg;
    if (msg && msg_len) snprintf(msg, msg_len, "%s", what);
    return rc;
  }
  *x = v;
  return AP_OK;
}
