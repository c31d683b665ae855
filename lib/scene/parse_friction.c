/* Scene keys of the contact modes of a rolling constraint (docs/scenes.md "Friction, slip and
 * lift-off"): `friction: {mu: 0.8, mu_kinetic: 0.6}`, `unilateral: true|false` and
 * `restitution: 0.5` into the constraint's ap_constraint_def (mu, mu_kinetic, unilateral,
 * restitution; the model checks the rest), and the listings' and outputs' view of them. */
#include <math.h>

#include "scene/scene_int.h"

static const char *const friction_keys[] = {"mu", "mu_kinetic", NULL};

int sc_parse_friction(sc_ctx *c, const sc_node *n, ap_constraint_def *d) {
  const sc_node *f = sc_map_get(n, "friction"), *u = sc_map_get(n, "unilateral");
  if (u && sc_get_bool(c, n, "unilateral", &d->unilateral)) return AP_ERR_ARG;
  if (sc_get_number(c, n, "restitution", &d->restitution)) return AP_ERR_ARG;
  const sc_node *e = sc_map_get(n, "restitution");
  if (e && !(d->restitution >= 0 && d->restitution <= 1))
    return sc_err(c, e, "restitution must lie between 0 and 1 (got %g)", d->restitution);
  if (!f) return AP_OK;
  if (sc_expect(c, f, SC_MAP) || sc_check_keys(c, f, friction_keys)) return AP_ERR_ARG;
  if (!sc_map_get(f, "mu")) return sc_err(c, f, "friction needs mu (e.g. {mu: 0.8})");
  if (sc_get_number(c, f, "mu", &d->mu) || sc_check_nonneg(c, f, "mu", d->mu) ||
      sc_get_number(c, f, "mu_kinetic", &d->mu_kinetic))
    return AP_ERR_ARG;
  const sc_node *k = sc_map_get(f, "mu_kinetic");
  if (k && !(d->mu_kinetic >= 0 && d->mu_kinetic <= d->mu))
    return sc_err(c, k, "mu_kinetic must lie between 0 and mu = %g (got %g)", d->mu,
                  d->mu_kinetic);
  return AP_OK;
}

int sc_con_has_modes(const sc_con *k) {
  const ap_constraint_def *d = &k->def;
  return d->kind == AP_CON_ROLLING && (d->mu >= 0 || d->unilateral == 1);
}

int sc_scene_has_modes(const sc_scene *s) {
  for (int i = 0; i < s->nc; i++)
    if (sc_con_has_modes(&s->cons[i])) return 1;
  return 0;
}

const char *sc_con_kind_text(const sc_con *k, const char *const *kinds) {
  const ap_constraint_def *d = &k->def;
  if (!sc_con_has_modes(k)) return kinds[d->kind];
  int uni = d->unilateral == 1 || (d->unilateral < 0 && d->mu >= 0);
  if (d->mu < 0) return "rolling, unilateral (perfectly rough; modes rolling, airborne)";
  return uni ? "rolling with friction, unilateral (modes rolling, sliding, airborne)"
             : "rolling with friction, bilateral (modes rolling, sliding)";
}
