/* Contact modes for the differential tester's random models (docs/testing.md, "Contact
 * modes"): a free sphere rolling on the ground, or the wheels of a two-wheeled chassis made
 * free (a planar chassis refuses friction), get `friction: {mu, mu_kinetic}`, `unilateral`
 * and `restitution` (docs/scenes.md, "Friction, slip and lift-off"), in models with gravity.
 *
 * The numbers come from a stream of their own (seeded from the model's seed), so that a
 * model without such a contact is the same as before contact modes joined the tester. Initial
 * states are consistent by construction: the sphere's free joint has no frame, its height is
 * its radius (on the ground; vz 0) or up to 8 cm above it (airborne, a unilateral contact,
 * falling onto the ground within the run); the free chassis stands at the wheels' height. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen.h"
#include "testrand.h"

void dt_add_contact_modes(uint64_t seed, dt_model *m);

static double ur(uint64_t *s, double a, double b) { return a + (b - a) * ap_test_urand(s); }
static int chance(uint64_t *s, double p) { return ap_test_urand(s) < p; }

/* Append the contact keys to a rolling constraint's flow mapping (text ends with "}"). */
static void contact_keys(uint64_t *s, dt_model *m, char *text) {
  size_t l = strlen(text);
  if (l < 2 || l + 120 >= DT_TXT) return;
  m->expect_tree = 0;   /* the tree path refuses contacts with modes (model/contact.c) */
  text[l - 1] = 0;
  int fr = chance(s, 0.8), uni = fr ? chance(s, 0.75) : 1;
  char *end = text + strlen(text);
  size_t room = DT_TXT - strlen(text);
  if (fr) {
    double mu = ur(s, 0.05, 1);
    int n = snprintf(end, room, ", friction: {mu: %.4g, mu_kinetic: %.4g}", mu,
                     mu * ur(s, 0.5, 1));
    end += n, room -= (size_t)n;
  }
  int n = snprintf(end, room, "%s", !uni ? ", unilateral: false" : fr ? "" : ", unilateral: true");
  end += n, room -= (size_t)n;
  if (uni && chance(s, 0.4)) {
    n = snprintf(end, room, ", restitution: %.3g", ur(s, 0.1, 0.8));
    end += n, room -= (size_t)n;
  }
  snprintf(end, room, "}");
}

/* The radius of a sphere body ("radius: R" in its text), 0 when none. */
static double radius_of(const dt_body *b) {
  const char *r = strstr(b->body, "radius: ");
  return r ? atof(r + 8) : 0;
}

/* Put the free sphere i on the ground (or above it) with a consistent initial state. */
static void sphere_state(uint64_t *s, dt_body *b, double r, int airborne) {
  snprintf(b->joint, DT_TXT, "{kind: free}");
  double z = airborne ? r + ur(s, 0.005, 0.08) : r;
  char rest[DT_TXT] = "";
  const char *o = strstr(b->init, "heading:");
  if (!o) o = strstr(b->init, "yaw:");
  if (o) snprintf(rest, sizeof rest, ", %s", o);   /* orientation and rates, with the "}" */
  else snprintf(rest, sizeof rest, "}");
  snprintf(b->init, DT_TXT, "{x: %.4g, y: %.4g, z: %.6g, vx: %.4g, vy: %.4g, vz: %.4g%s",
           ur(s, -.5, .5), ur(s, -.5, .5), z, ur(s, -1, 1), ur(s, -1, 1),
           airborne ? ur(s, -1, 0.5) : 0.0, rest);
}

static int has_gravity(const dt_model *m) {
  for (int e = 0; e < m->ne; e++)
    if (m->e[e].live && strstr(m->e[e].text, "gravity")) return 1;
  return 0;
}

/* The vehicle's chassis (a planar joint at the wheels' height) made free. */
static int free_chassis(uint64_t *s, dt_model *m, int ic) {
  dt_body *c = &m->b[ic];
  const char *z = strstr(c->joint, "pos: [0, 0, ");
  if (c->kind != DT_PLANAR || !z) return 0;
  double h = atof(z + 12);
  c->kind = DT_FREE;
  snprintf(c->joint, DT_TXT, "{kind: free, parent_frame: {pos: [0, 0, %.4g]}}", h);
  snprintf(c->init, DT_TXT, "{vx: %.4g, omega: [0, 0, %.4g]}", ur(s, -1, 1), ur(s, -1, 1));
  return 1;
}

void dt_add_contact_modes(uint64_t seed, dt_model *m) {
  uint64_t st = seed * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull, *s = &st;
  for (int i = 0; i < 4; i++) ap_test_urand(s);
  if (!has_gravity(m)) return;
  int chassis_free = -1;
  for (int c = 0; c < m->nc; c++) {
    int i = m->c[c].refs[0];
    if (!m->c[c].live || i < 0 || strncmp(m->c[c].text, "{kind: rolling,", 15)) continue;
    dt_body *b = &m->b[i];
    if (b->kind == DT_FREE && b->shape == DT_SH_SPHERE && b->parent < 0 && chance(s, 0.6)) {
      contact_keys(s, m, m->c[c].text);
      int uni = !strstr(m->c[c].text, "unilateral: false");
      sphere_state(s, b, radius_of(b), uni && chance(s, 0.4));
    } else if (b->kind == DT_REVOLUTE && b->parent >= 0 && m->b[b->parent].kind != DT_FREE &&
               chassis_free < 0 && chance(s, 0.4)) {
      chassis_free = free_chassis(s, m, b->parent) ? b->parent : -2;
    }
    if (chassis_free >= 0 && b->kind == DT_REVOLUTE && b->parent == chassis_free)
      contact_keys(s, m, m->c[c].text);
  }
}
