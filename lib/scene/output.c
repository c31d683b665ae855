/* Scene outputs: the column names of a CSV row and their values at a simulation's state
 * (docs/scenes.md "output"; docs/cli.md "CSV").
 *
 * Columns, in this order: t; coordinates (model names, e.g. disk.x, disk.qw); speeds
 * (disk.wx); angles (disk.heading, disk.tilt, disk.spin: Z-X-Z of each quaternion joint,
 * unwrapped from row to row so that a steady spin gives a straight line); com (disk.com.x);
 * contacts (disk.contact.x, .y, for plane-contact joints, then for bodies held by a wheel
 * contact); poses (per body: disk.pos.x, .y, .z, the body origin, and
 * disk.rot.w, .x, .y, .z, the unit quaternion of the body axes in world axes, w >= 0, from
 * ap_quat_from_matrix of ap_body_get_state's R); energy (kinetic, potential, energy, energy_error = E - E(t0));
 * residual (max |A v + a0|); reactions (lambda.<row>); contact forces (per rolling constraint,
 * named by its body: disk.contact.Fx, .Fy, .Fz, .friction_ratio, from ap_body_contact_force
 * with the simulation's multipliers, IDA's own in DAE mode); then the named channels and the
 * driven coordinates (channels.c). Only the channels asked for are
 * evaluated. Invariant: sc_out_names and sc_out_row agree on the count and the order. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "scene/scene_int.h"

static const double two_pi = 6.28318530717958647692;

static int quat_joint(const sc_joint *j) {
  return j->def.kind == AP_JOINT_BALL || j->def.kind == AP_JOINT_FREE ||
         j->def.kind == AP_JOINT_PLANE_CONTACT;
}

/* Free coordinates of a quaternion joint before its quaternion (driven ones are not in q). */
static int quat_offset(const sc_joint *j) {
  int lin = j->def.kind == AP_JOINT_FREE ? 3 : j->def.kind == AP_JOINT_PLANE_CONTACT ? 2 : 0;
  int off = 0;
  for (int i = 0; i < lin; i++) off += j->def.drive[i] == NULL;
  return off;
}

static int push(sc_out *o, const char *a, const char *b) {
  size_t len = strlen(a) + strlen(b) + 1;
  char *s = malloc(len), **cols = realloc(o->cols, sizeof *cols * (size_t)(o->ncols + 1));
  if (!s || !cols) {
    free(s);
    if (cols) o->cols = cols;
    return AP_ERR_NOMEM;
  }
  snprintf(s, len, "%s%s", a, b);
  o->cols = cols;
  o->cols[o->ncols++] = s;
  return AP_OK;
}

/* Is body b held by a wheel contact (a rolling constraint on a body that is not on a
 * plane-contact joint)? Its contact point is a `contacts` column like a plane contact's. */
static int wheel_body(const sc_scene *s, int b) {
  for (int j = 0; j < s->nj; j++)
    if (s->joints[j].def.child == b && s->joints[j].def.kind == AP_JOINT_PLANE_CONTACT) return 0;
  for (int i = 0; i < s->nc; i++)
    if (s->cons[i].def.kind == AP_CON_ROLLING && s->cons[i].def.body == b) return 1;
  return 0;
}

static int body_cols(sc_out *o, const sc_scene *s, unsigned ch) {
  static const char *const ang[] = {".heading", ".tilt", ".spin"};
  static const char *const com[] = {".com.x", ".com.y", ".com.z"};
  int rc = AP_OK;
  for (int j = 0; rc == AP_OK && (ch & SC_OUT_ANGLES) && j < s->nj; j++)
    for (int i = 0; rc == AP_OK && i < 3 && quat_joint(&s->joints[j]); i++)
      rc = push(o, s->bodies[s->joints[j].def.child].name, ang[i]);
  for (int b = 0; rc == AP_OK && (ch & SC_OUT_COM) && b < s->nb; b++)
    for (int i = 0; rc == AP_OK && i < 3; i++) rc = push(o, s->bodies[b].name, com[i]);
  for (int j = 0; rc == AP_OK && (ch & SC_OUT_CONTACTS) && j < s->nj; j++)
    if (s->joints[j].def.kind == AP_JOINT_PLANE_CONTACT) {
      const char *bn = s->bodies[s->joints[j].def.child].name;
      rc = push(o, bn, ".contact.x");
      if (rc == AP_OK) rc = push(o, bn, ".contact.y");
    }
  for (int b = 0; rc == AP_OK && (ch & SC_OUT_CONTACTS) && b < s->nb; b++)
    if (wheel_body(s, b)) {
      rc = push(o, s->bodies[b].name, ".contact.x");
      if (rc == AP_OK) rc = push(o, s->bodies[b].name, ".contact.y");
    }
  static const char *const pose[] = {".pos.x", ".pos.y", ".pos.z", ".rot.w", ".rot.x", ".rot.y",
                                     ".rot.z"};
  for (int b = 0; rc == AP_OK && (ch & SC_OUT_POSES) && b < s->nb; b++)
    for (int i = 0; rc == AP_OK && i < 7; i++) rc = push(o, s->bodies[b].name, pose[i]);
  return rc;
}

int sc_out_names(sc_out *o, const sc_scene *s, const ap_model *m) {
  unsigned ch = s->channels;
  int rc = push(o, "t", "");
  for (int i = 0; rc == AP_OK && (ch & SC_OUT_COORDS) && i < ap_model_n(m); i++)
    rc = push(o, ap_model_coord_name(m, i), "");
  for (int i = 0; rc == AP_OK && (ch & SC_OUT_SPEEDS) && i < ap_model_k(m); i++)
    rc = push(o, ap_model_speed_name(m, i), "");
  if (rc == AP_OK) rc = body_cols(o, s, ch);
  static const char *const en[] = {"kinetic", "potential", "energy", "energy_error"};
  for (int i = 0; rc == AP_OK && (ch & SC_OUT_ENERGY) && i < 4; i++) rc = push(o, en[i], "");
  if (rc == AP_OK && (ch & SC_OUT_RESIDUAL)) rc = push(o, "residual", "");
  for (int i = 0; rc == AP_OK && (ch & SC_OUT_REACTIONS) && i < ap_model_b(m); i++)
    rc = push(o, "lambda.", ap_model_constraint_name(m, i));
  static const char *const cf[] = {".contact.Fx", ".contact.Fy", ".contact.Fz",
                                   ".contact.friction_ratio"};
  for (int i = 0; rc == AP_OK && (ch & SC_OUT_CONTACT_FORCES) && i < s->nc; i++) {
    for (int j = 0; rc == AP_OK && j < 4 && s->cons[i].def.kind == AP_CON_ROLLING; j++)
      rc = push(o, s->bodies[s->cons[i].def.body].name, cf[j]);
    if (rc == AP_OK && sc_con_has_modes(&s->cons[i]))   /* 0 rolling, 1 sliding, 2 airborne */
      rc = push(o, s->bodies[s->cons[i].def.body].name, ".contact.mode");
  }
  char buf[160];
  for (int i = 0; rc == AP_OK && i < sc_named_count(s, m); i++)
    rc = push(o, sc_named_column(s, i, buf, sizeof buf), "");
  if (rc == AP_OK) o->angles = calloc((size_t)3 * (size_t)s->nj + 1, sizeof *o->angles);
  return rc == AP_OK && o->angles ? AP_OK : AP_ERR_NOMEM;
}

void sc_out_free(sc_out *o) {
  for (int i = 0; i < o->ncols; i++) free(o->cols[i]);
  free(o->cols);
  free(o->angles);
  memset(o, 0, sizeof *o);
}

/* x moved by a multiple of 2 pi to be nearest to prev. */
static double unwrap(double x, double prev) {
  return x + two_pi * round((prev - x) / two_pi);
}

static int body_vals(sc_out *o, const sc_scene *s, const ap_model *m, ap_data *d, double *row,
                     int *c) {
  unsigned ch = s->channels;
  for (int j = 0; (ch & SC_OUT_ANGLES) && j < s->nj; j++) {
    if (!quat_joint(&s->joints[j])) continue;
    double e[3], *prev = o->angles + 3 * j;
    sc_quat_to_zxz(d->q + ap_joint_coord_index(m, j) + quat_offset(&s->joints[j]), e);
    for (int i = 0; i < 3; i++) row[(*c)++] = prev[i] = o->rows ? unwrap(e[i], prev[i]) : e[i];
  }
  for (int b = 0; (ch & SC_OUT_COM) && b < s->nb; b++) {
    ap_body_state st;
    if (ap_body_get_state(m, d, b, &st) != AP_OK) return AP_ERR_INTERNAL;
    for (int i = 0; i < 3; i++) row[(*c)++] = st.com[i];
  }
  for (int j = 0; (ch & SC_OUT_CONTACTS) && j < s->nj; j++) {
    if (s->joints[j].def.kind != AP_JOINT_PLANE_CONTACT) continue;
    ap_body_state st;
    if (ap_body_get_state(m, d, s->joints[j].def.child, &st) != AP_OK) return AP_ERR_INTERNAL;
    row[(*c)++] = st.contact[0], row[(*c)++] = st.contact[1];
  }
  for (int b = 0; (ch & SC_OUT_CONTACTS) && b < s->nb; b++) {
    if (!wheel_body(s, b)) continue;
    ap_body_state st;
    if (ap_body_get_state(m, d, b, &st) != AP_OK) return AP_ERR_INTERNAL;
    row[(*c)++] = st.has_contact ? st.contact[0] : NAN;
    row[(*c)++] = st.has_contact ? st.contact[1] : NAN;
  }
  for (int b = 0; (ch & SC_OUT_POSES) && b < s->nb; b++) {
    ap_body_state st;
    if (ap_body_get_state(m, d, b, &st) != AP_OK) return AP_ERR_INTERNAL;
    double *p = row + *c;
    memcpy(p, st.pos, sizeof st.pos);
    ap_quat_from_matrix(st.R, p + 3);
    if (p[3] < 0)
      for (int i = 3; i < 7; i++) p[i] = -p[i];
    *c += 7;
  }
  return AP_OK;
}

int sc_out_energy(const ap_model *m, ap_data *d, double *T, double *V) {
  return ap_body_energy(m, d, T, V);
}

int sc_out_row(sc_out *o, const sc_scene *s, const ap_model *m, ap_data *d, ap_sim *sim,
               double *row) {
  unsigned ch = s->channels;
  int n = ap_model_n(m), k = ap_model_k(m), b = ap_model_b(m), c = 0, rc = AP_OK;
  d->t = ap_sim_time(sim);
  memcpy(d->q, ap_sim_q(sim), sizeof(double) * (size_t)n);
  memcpy(d->v, ap_sim_v(sim), sizeof(double) * (size_t)k);
  row[c++] = d->t;
  for (int i = 0; (ch & SC_OUT_COORDS) && i < n; i++) row[c++] = d->q[i];
  for (int i = 0; (ch & SC_OUT_SPEEDS) && i < k; i++) row[c++] = d->v[i];
  if (ch & (SC_OUT_ANGLES | SC_OUT_COM | SC_OUT_CONTACTS | SC_OUT_POSES)) {
    if ((rc = ap_body_eval(m, d)) != AP_OK) return rc;
    if ((rc = body_vals(o, s, m, d, row, &c)) != AP_OK) return rc;
  }
  if (ch & SC_OUT_ENERGY) {
    double T = 0, V = 0;
    if ((rc = sc_out_energy(m, d, &T, &V)) != AP_OK) return rc;
    if (!o->rows) o->E0 = T + V;
    row[c++] = T, row[c++] = V, row[c++] = T + V, row[c++] = T + V - o->E0;
  }
  if (ch & SC_OUT_RESIDUAL) {   /* contact modes: the rows of the simulation's modes */
    const ap_data *dr = sc_scene_has_modes(s) ? ap_sim_data(sim) : d;
    if (dr == d) d->basis = AP_BASIS_NONE;
    if (dr == d && (rc = ap_fwd_position(m, d)) != AP_OK) return rc;
    row[c++] = ap_constraint_residual(dr, d->v);
  }
  if ((ch & SC_OUT_REACTIONS) && b > 0) {
    const double *lambda = NULL;
    if ((rc = ap_sim_reactions(sim, &lambda)) != AP_OK) return rc;
    for (int i = 0; i < b; i++) row[c++] = lambda[i];
  }
  if ((ch & SC_OUT_CONTACT_FORCES) && b > 0) {
    const double *lambda = NULL;
    if ((rc = ap_sim_reactions(sim, &lambda)) != AP_OK) return rc;
    for (int i = 0; i < s->nc; i++) {
      if (s->cons[i].def.kind != AP_CON_ROLLING) continue;
      ap_contact_force f;
      if ((rc = ap_body_contact_force(m, ap_sim_data(sim), lambda, i, &f)) != AP_OK) return rc;
      row[c++] = f.force[0] + 0.0, row[c++] = f.force[1] + 0.0, row[c++] = f.force[2];
      row[c++] = f.friction_ratio;
      if (sc_con_has_modes(&s->cons[i])) row[c++] = ap_sim_contact_mode(sim, i);
    }
  }
  if (s->nnamed || (ch & SC_OUT_DRIVEN)) {
    int nv = sc_named_values(s, m, d, row + c);
    if (nv < 0) return nv;
    c += nv;
  }
  o->rows++;
  return c == o->ncols ? AP_OK : AP_ERR_INTERNAL;
}
