/* Loop closures for the differential tester's random models: the model without the closure is
 * loaded through the public scene API, its initial state made consistent, and the world
 * position of a random point of a random body read from the library's kinematics
 * (ap_body_get_state); the closure (coincident on some world axes, point on a line, point on a
 * plane) then holds at that state, to the 4 digits the scene text keeps (the library assembles
 * the rest). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "gen.h"
#include "testrand.h"

void dt_add_closure(uint64_t *s, dt_model *m);

enum { TEXT_LEN = 32768 };

/* World point x = pos + R p of body `name` (R column-major); 0 when found. */
static int world_point(const ap_model *mod, const ap_data *d, int body, const double p[3],
                       double x[3], ap_body_state *st) {
  if (ap_body_get_state(mod, d, body, st) != AP_OK) return -1;
  for (int i = 0; i < 3; i++)
    x[i] = st->pos[i] + st->R[i] * p[0] + st->R[i + 3] * p[1] + st->R[i + 6] * p[2];
  return 0;
}

/* Pick a live body other than `not`, -1 when there is none. */
static int live_body(uint64_t *s, const dt_model *m, int not) {
  for (int tries = 0; tries < 16; tries++) {
    int i = (int)(ap_test_urand(s) * m->nb);
    if (m->b[i].live && i != not && m->b[i].kind != DT_PLANE) return i;
  }
  return -1;
}

static void closure_text(uint64_t *s, dt_item *c, int a, const double p[3], int b2,
                         const double p2[3]) {
  static const char *const axes[] = {"xyz", "xy", "yz", "xz", "x", "z"};
  double x = ap_test_urand(s), dir[3];
  for (int i = 0; i < 3; i++) dir[i] = 2 * ap_test_urand(s) - 1;
  const char *kind = x < 0.5 ? "coincident" : x < 0.75 ? "point_on_line" : "point_on_plane";
  int used = snprintf(c->text, DT_TXT, "{kind: %s, body: b%d, point: [%.4g, %.4g, %.4g]", kind,
                      a, p[0], p[1], p[2]);
  if (b2 >= 0) used += snprintf(c->text + used, DT_TXT - (size_t)used, ", body2: b%d", b2);
  used += snprintf(c->text + used, DT_TXT - (size_t)used, ", point2: [%.17g, %.17g, %.17g]", p2[0],
                   p2[1], p2[2]);
  if (x < 0.5)
    snprintf(c->text + used, DT_TXT - (size_t)used, ", axes: %s}",
             axes[(int)(ap_test_urand(s) * 6)]);
  else
    snprintf(c->text + used, DT_TXT - (size_t)used, ", direction: [%.4g, %.4g, %.4g]}", dir[0],
             dir[1], dir[2]);
}

void dt_add_closure(uint64_t *s, dt_model *m) {
  int a = live_body(s, m, -1), b2 = ap_test_urand(s) < 0.6 ? -1 : live_body(s, m, a);
  if (a < 0 || m->nc >= DT_MAXC) return;
  char *text = malloc(TEXT_LEN), msg[512];
  ap_scene *sc = NULL;
  ap_data *d = NULL;
  double *q = NULL, *v = NULL;
  dt_write(m, NULL, text, TEXT_LEN);
  if (ap_scene_load_string(text, strlen(text), "closure", NULL, 0, &sc, msg, sizeof msg)) goto out;
  const ap_model *mod = ap_scene_model(sc);
  q = calloc((size_t)ap_model_n(mod) + 1, sizeof *q);
  v = calloc((size_t)ap_model_k(mod) + 1, sizeof *v);
  if (ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg) ||
      ap_data_create(mod, &d) != AP_OK)
    goto out;
  memcpy(d->q, q, sizeof *q * (size_t)d->n);
  memcpy(d->v, v, sizeof *v * (size_t)d->k);
  if (ap_body_eval(mod, d) != AP_OK) goto out;
  char name[16];
  snprintf(name, sizeof name, "b%d", a);
  double p[3], x[3], p2[3], x2[3], zero[3] = {0, 0, 0};
  for (int i = 0; i < 3; i++) p[i] = 0.2 * (2 * ap_test_urand(s) - 1);
  snprintf(msg, sizeof msg, "%.4g %.4g %.4g", p[0], p[1], p[2]);
  if (sscanf(msg, "%lf %lf %lf", &p[0], &p[1], &p[2]) != 3) goto out;   /* as written */
  ap_body_state st, st2;
  if (world_point(mod, d, ap_model_find_body(mod, name), p, x, &st)) goto out;
  memcpy(p2, x, sizeof p2);
  if (b2 >= 0) {
    snprintf(name, sizeof name, "b%d", b2);
    if (world_point(mod, d, ap_model_find_body(mod, name), zero, x2, &st2)) goto out;
    for (int i = 0; i < 3; i++)   /* p2 = R2^T (x - pos2) */
      p2[i] = st2.R[3 * i] * (x[0] - x2[0]) + st2.R[3 * i + 1] * (x[1] - x2[1]) +
              st2.R[3 * i + 2] * (x[2] - x2[2]);
  }
  dt_item *c = &m->c[m->nc++];
  c->live = 1, c->refs[0] = a, c->refs[1] = b2;
  closure_text(s, c, a, p, b2, p2);
  m->expect_tree = 0;
out:
  ap_data_free(d);
  ap_scene_free(sc);
  free(q), free(v), free(text);
}
