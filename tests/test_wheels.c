/* Wheel contacts on any body (contact.c): the rows against finite differences of the contact
 * point, gamma against finite differences along the motion (fdcheck.h), the broken gamma, lying
 * flat, and the two forms of one rolling disk.
 *
 * Rows: with a fixed ground the rolling rows .x .y .z are the material contact point's velocity
 * vP, so they must equal d/ds of o + R c_b (c_b of s = 0 held on the body), and the contact row
 * .z also d/ds of the geometric contact point's height (the constraint's phi); the wheel knife
 * row is n . vP with n = R e_z. Same Richardson differences and tolerance as fdcheck.h.
 *
 * Two forms of one disk: a thin disk on a plane-contact joint with rolling (the joint keeps it
 * on the plane) and the same disk on a free joint with the wheel contact (rolling plus the
 * contact row .z, held by projection after each step). Both describe the same motion and, in
 * minimal mode, follow it step for step to round-off (test_two_forms). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/sim.h>

#include "fdcheck.h"

static const char *const shape_names[] = {"none", "point", "sphere", "ellipsoid", "disk",
                                          "torus"};

static ap_model *compile(ap_builder *b) {
  ap_model *m = NULL;
  int rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) fprintf(stderr, "compile failed: %s\n", ap_builder_message(b));
  AP_CHECK(rc == AP_OK);
  ap_builder_free(b);
  return m;
}

static void set_ground(ap_constraint_def *c, int ground) {
  if (ground == 1) {
    c->ground.kind = AP_GROUND_TURNTABLE, c->ground.omega_fn = f_omega;
    c->ground.center[0] = -0.4, c->ground.center[1] = 0.25;
  } else if (ground == 2) {
    c->ground.kind = AP_GROUND_TRANSLATING, c->ground.velocity_fn[1] = f_vel;
    c->ground.velocity[0] = -0.2;
  }
}

/* A carrier on a free joint and a wheel of the given shape on a joint of the carrier (ball:
 * any orientation; revolute: a wheel on an axle), random frames, coms and inertias; the wheel
 * rolls (knife = 0) or has a wheel knife edge (knife = 1); gravity. */
static ap_model *wheel_model(ap_shape_kind kind, ap_joint_kind jk, int ground, int knife,
                             int no_spin) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("wheel on a carrier", &b) == AP_OK);
  ap_body_def bd = ap_body_def_default();
  bd.name = "carrier", bd.mass = 2.0;
  rand_vec(bd.com, 3, 0.2), rand_inertia(bd.inertia, 0.2);
  AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
  bd.name = "wheel", bd.mass = 1.3;
  bd.shape.kind = kind, bd.shape.radius = 0.4, bd.shape.tube = 0.07;
  bd.shape.semi_axes[0] = 0.5, bd.shape.semi_axes[1] = 0.3, bd.shape.semi_axes[2] = 0.2;
  rand_vec(bd.com, 3, 0.1), rand_inertia(bd.inertia, 0.05);
  AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.child = 0;
  rand_frame(&j.parent_frame), rand_frame(&j.child_frame);
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  j.kind = jk, j.parent = 0, j.child = 1;
  rand_frame(&j.parent_frame), rand_frame(&j.child_frame), rand_vec(j.axis, 3, 1.0);
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "contact", c.body = 1, c.no_spin = no_spin;
  if (knife) c.kind = AP_CON_KNIFE_EDGE, c.wheel = 1;
  set_ground(&c, ground);
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  return compile(b);
}

/* The rows of the contact (fixed ground) against the motion of the contact point. */
static double row_error(const ap_model *m, const meas *a, const meas *der, int knife) {
  int r0 = ap_constraint_row_index(m, 0), nr = m->b - r0;
  double e = 0.0;
  if (knife) {   /* .side = n . vP, n = R e_z of s = 0; then .z */
    const double *R = a->R[1];
    double nv = R[6] * der->xm[1][0] + R[7] * der->xm[1][1] + R[8] * der->xm[1][2];
    e = fmax(e, err_rel(&a->c[r0], &nv, 1));
  } else {
    e = fmax(e, err_rel(&a->c[r0], der->xm[1], 2));   /* .x .y */
  }
  e = fmax(e, err_rel(&a->c[r0 + nr - 1], &der->xm[1][2], 1));   /* .z: material point */
  e = fmax(e, err_rel(&a->c[r0 + nr - 1], &der->zc[1], 1));      /* .z: phi' */
  return e;
}

static void test_fd_wheels(void) {
  printf("wheel contacts, finite differences (relative errors, worst of the samples):\n");
  for (int knife = 0; knife < 2; knife++)
    for (int kind = knife ? AP_SHAPE_DISK : AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++)
      for (int ground = 0; ground < 3; ground++)
        for (int jk = 0; jk < 2; jk++) {
          char label[64];
          ap_joint_kind joint = jk ? AP_JOINT_REVOLUTE : AP_JOINT_BALL;
          snprintf(label, sizeof label, "%s %s, %s, ground %d", shape_names[kind],
                   knife ? "knife" : "rolling", jk ? "revolute" : "ball", ground);
          ap_model *m = wheel_model((ap_shape_kind)kind, joint, ground, knife, ground == 1);
          fd_many(label, m, 6, 0, kind >= AP_SHAPE_DISK ? 0.2 : 0.0);
          if (ground == 0) {   /* rows against the contact point's motion */
            ap_data *d = NULL;
            AP_CHECK(ap_data_create(m, &d) == AP_OK);
            double q[MAXK], v[MAXK], t, worst = 0.0;
            static meas a, der;
            for (int s = 0; s < 4; s++) {
              fd_result r;
              do rand_state(m, q, v, &t);
              while (measure(m, d, t, q, v, &a) != AP_OK || fabs(a.R[1][8]) > 0.98);
              AP_CHECK(fd_check(m, d, t, q, v, 1e-3, &r, &a, &der) == AP_OK);
              worst = fmax(worst, row_error(m, &a, &der, knife));
            }
            printf("    rows vs the contact point's motion: %.1e\n", worst);
            AP_CHECK_LE(worst, FD_TOL);
            ap_data_free(d);
          }
          ap_model_free(m);
        }
}

/* gamma without the term of the contact point moving over the body surface fails the check. */
static void test_broken_gamma(void) {
  printf("wheel contact gamma without the surface-motion term (must fail the check):\n");
  for (int knife = 0; knife < 2; knife++)
    for (int kind = knife ? AP_SHAPE_DISK : AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++) {
      ap_model *m = wheel_model((ap_shape_kind)kind, AP_JOINT_BALL, 0, knife, 0);
      ap_data *d = NULL;
      AP_CHECK(ap_data_create(m, &d) == AP_OK);
      double good = 0.0, bad = 1e300;
      for (int s = 0; s < 4; s++) {
        static meas a, der;
        double q[MAXK], v[MAXK], t, gb[MAXR], mb[MAXR], mg[MAXR];
        fd_result r;
        do rand_state(m, q, v, &t);
        while (measure(m, d, t, q, v, &a) != AP_OK || fabs(a.R[1][8]) > 0.95);
        AP_CHECK(fd_check(m, d, t, q, v, 1e-3, &r, &a, &der) == AP_OK);
        AP_CHECK(measure(m, d, t, q, v, &a) == AP_OK);
        ap_con_rolling_gamma(ap_bm(m), ap_bm_scratch(d), 0, 0, gb);
        for (int i = 0; i < m->b; i++) mb[i] = -gb[i], mg[i] = -a.gamma[i];
        good = fmax(good, err_rel(mg, der.c, m->b));
        bad = fmin(bad, err_rel(mb, der.c, m->b));
      }
      printf("  %-9s %-7s with the term %.1e; without it at least %.1e\n", shape_names[kind],
             knife ? "knife" : "rolling", good, bad);
      AP_CHECK_LE(good, FD_TOL);
      AP_CHECK(bad > 100 * FD_TOL);   /* every sample flags the broken gamma */
      ap_data_free(d);
      ap_model_free(m);
    }
}

/* A disk on a free joint with the wheel contact. */
static ap_model *free_disk(ap_shape_kind kind) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("free disk", &b) == AP_OK);
  ap_body_def bd = ap_body_def_default();
  bd.name = "wheel", bd.shape.kind = kind, bd.shape.radius = 0.3, bd.shape.tube = 0.05;
  AP_CHECK(ap_body_def_uniform(&bd, 1.5) == AP_OK);
  AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.child = 0;
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  return compile(b);
}

/* A disk or torus wheel whose axis is vertical: a recoverable error naming the body and the
 * constraint, never NaN; the projection of q reports it too. */
static void test_flat(void) {
  for (int kind = AP_SHAPE_DISK; kind <= AP_SHAPE_TORUS; kind++) {
    ap_model *m = free_disk((ap_shape_kind)kind);
    ap_data *d = NULL;
    AP_CHECK(ap_data_create(m, &d) == AP_OK);
    double q[7] = {0.1, 0.2, 0.3, 1, 0, 0, 0}, change;
    memcpy(d->q, q, sizeof q);
    d->t = 0.2, d->basis = AP_BASIS_NONE;
    int rc = ap_fwd_position(m, d);
    printf("%s wheel lying flat: status %d: %s\n", shape_names[kind], rc, d->msg);
    AP_CHECK_EQ_INT(rc, AP_RECOVERABLE);
    AP_CHECK(strstr(d->msg, "body 'wheel'") && strstr(d->msg, "constraint 'roll'") &&
             strstr(d->msg, "lies flat"));
    rc = ap_body_project_q(m, d, q, &change);
    AP_CHECK(rc != AP_OK && strstr(d->msg, "body 'wheel'"));
    ap_data_free(d);
    ap_model_free(m);
  }
}

/* ---- one disk, two forms -------------------------------------------------------------------- */

/* A thin uniform disk (radius 0.3 m, 1.5 kg) on a plane-contact joint with rolling (form 0) or
 * on a free joint with the wheel contact (form 1), under gravity. */
static ap_model *disk_form(int form) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create(form ? "disk, free joint" : "disk, plane contact", &b) == AP_OK);
  ap_body_def bd = ap_body_def_default();
  bd.name = "disk", bd.shape.kind = AP_SHAPE_DISK, bd.shape.radius = 0.3;
  AP_CHECK(ap_body_def_uniform(&bd, 1.5) == AP_OK);
  AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.kind = form ? AP_JOINT_FREE : AP_JOINT_PLANE_CONTACT, j.child = 0;
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  return compile(b);
}

/* The initial state of either form: leaning 30 degrees from upright, spinning at -6 rad/s about
 * its axis and turning at 4 rad/s about the vertical; the centre's velocity completed from the
 * constraints; the free form's height r cos(lean) from its contact row. */
static void disk_initial(const ap_model *m, int form, double *q, double *v) {
  double ez[3] = {0, 0, 1}, ex[3] = {1, 0, 0}, qa[4], R[9], w[3];
  int o = form ? 3 : 2, given[6] = {0};
  ap_quat_from_axis_angle(ex, 60 * RS_PI_ / 180, qa);   /* tilt: axis 60 deg from vertical */
  memset(q, 0, sizeof(double) * (size_t)m->n);
  memcpy(q + o, qa, sizeof qa);
  if (form) q[2] = 0.3 * sin(60 * RS_PI_ / 180);
  ap_quat_to_matrix(qa, R);
  for (int i = 0; i < 3; i++) w[i] = -6.0 * R[6 + i] + 4.0 * ez[i];
  memset(v, 0, sizeof(double) * (size_t)m->k);
  for (int i = 0; i < 3; i++) v[o + i] = w[i], given[o + i] = 1;   /* the angular velocity */
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  AP_CHECK(ap_body_complete_speeds(m, d, q, given, v) == AP_OK);
  ap_data_free(d);
}

/* Both forms in each mode at rtol 1e-12 over 3 s (about 1300 steps): the centre (x, y) and the
 * orientation agree to 1.4e-13 (minimal: the round-off of the steps), 1.3e-12 (projected) and
 * 1.1e-10 (DAE: IDA's own error at this rtol, different in each form); bounds 10 rtol in the
 * Appell modes, 1e3 rtol in DAE. The free form's contact point stays on the plane (projection
 * after each step; GGL rows in DAE). */
static void test_two_forms(void) {
  printf("one rolling disk, plane-contact joint vs free joint with the wheel contact:\n");
  ap_model *m0 = disk_form(0), *m1 = disk_form(1);
  double q0[6], v0[5], q1[7], v1[6];
  disk_initial(m0, 0, q0, v0);
  disk_initial(m1, 1, q1, v1);
  for (int i = 0; i < 3; i++) AP_CHECK_NEAR(v0[2 + i], v1[3 + i], 1e-15);
  AP_CHECK_NEAR(v0[0], v1[0], 1e-14);
  AP_CHECK_NEAR(v0[1], v1[1], 1e-14);
  static const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  static const char *const names[3] = {"minimal", "projected", "dae"};
  for (int mi = 0; mi < 3; mi++) {
    ap_sim_def def = ap_sim_def_default();
    def.mode = modes[mi], def.rtol = 1e-12, def.atol = 1e-14;
    char msg[512];
    ap_sim *s0 = NULL, *s1 = NULL;
    int rc0 = ap_sim_create(m0, &def, 0.0, q0, v0, &s0, msg, sizeof msg);
    if (rc0 != AP_OK) fprintf(stderr, "%s\n", msg);
    int rc1 = ap_sim_create(m1, &def, 0.0, q1, v1, &s1, msg, sizeof msg);
    if (rc1 != AP_OK) fprintf(stderr, "%s\n", msg);
    AP_CHECK(rc0 == AP_OK && rc1 == AP_OK);
    double dpos = 0.0, dquat = 0.0, height = 0.0;
    for (int i = 1; rc0 == AP_OK && rc1 == AP_OK && i <= 30; i++) {
      rc0 = ap_sim_advance(s0, 0.1 * i), rc1 = ap_sim_advance(s1, 0.1 * i);
      AP_CHECK(rc0 == AP_OK && rc1 == AP_OK);
      const double *a = ap_sim_q(s0), *b = ap_sim_q(s1);
      dpos = fmax(dpos, fmax(fabs(a[0] - b[0]), fabs(a[1] - b[1])));
      for (int k = 0; k < 4; k++) dquat = fmax(dquat, fabs(a[2 + k] - b[3 + k]));
      ap_body_state st;
      ap_body_get_state(m1, ap_sim_data(s1), 0, &st);
      height = fmax(height, fabs(st.contact[2]));
    }
    /* The contact force: the plane-contact joint's normal force comes from Newton's law, the
     * wheel contact's is the multiplier of its row .z; friction: the rolling multipliers. */
    const double *l0 = NULL, *l1 = NULL;
    ap_contact_force f0, f1;
    AP_CHECK(ap_sim_reactions(s0, &l0) == AP_OK && ap_sim_reactions(s1, &l1) == AP_OK);
    AP_CHECK(ap_body_contact_force(m0, ap_sim_data(s0), l0, 0, &f0) == AP_OK);
    AP_CHECK(ap_body_contact_force(m1, ap_sim_data(s1), l1, 0, &f1) == AP_OK);
    double dforce = 0.0;
    for (int i = 0; i < 3; i++) dforce = fmax(dforce, fabs(f0.force[i] - f1.force[i]));
    ap_sim_stats st0, st1;
    ap_sim_get_stats(s0, &st0), ap_sim_get_stats(s1, &st1);
    printf("  %-9s centre %.1e m, quaternion %.1e, contact height %.1e m, contact force %.1e N "
           "(F_n %.6f N); steps %ld / %ld\n", names[mi], dpos, dquat, height, dforce, f1.normal,
           st0.steps, st1.steps);
    AP_CHECK_LE(dforce, 1e-9 * fabs(f0.normal));
    double bound = (mi == 2 ? 1e3 : 10) * def.rtol;
    AP_CHECK_LE(dpos, bound);
    AP_CHECK_LE(dquat, bound);
    AP_CHECK_LE(height, 1e-12);
    ap_sim_free(s0), ap_sim_free(s1);
  }
  ap_model_free(m0), ap_model_free(m1);
}

/* Released at rest leaning 0.5 rad from upright, the disk falls flat in both forms: the run
 * stops with an error naming the body at the same time (the wheel contact's tracking of the
 * contact point round the rim is the plane-contact joint's). */
static void test_falls_flat(void) {
  double t_stop[2] = {0, 0}, ex[3] = {1, 0, 0};
  for (int form = 0; form < 2; form++) {
    ap_model *m = disk_form(form);
    double q[7] = {0}, v[6] = {0}, tilt = 0.5 * RS_PI_ - 0.5;
    int o = form ? 3 : 2;
    ap_quat_from_axis_angle(ex, tilt, q + o);
    if (form) q[2] = 0.3 * sin(tilt);
    ap_sim_def def = ap_sim_def_default();
    def.rtol = 1e-10, def.atol = 1e-12;
    char msg[512];
    ap_sim *s = NULL;
    AP_CHECK(ap_sim_create(m, &def, 0.0, q, v, &s, msg, sizeof msg) == AP_OK);
    int rc = s ? ap_sim_advance(s, 3.0) : AP_OK;
    const char *em = s ? ap_sim_message(s) : "";
    t_stop[form] = s ? ap_sim_time(s) : 0.0;
    printf("  %s: status %d at t = %.6f: %.90s...\n", form ? "free joint + wheel contact"
           : "plane-contact joint       ", rc, t_stop[form], em);
    AP_CHECK(rc < 0 && strstr(em, "body 'disk'") && strstr(em, "flat"));
    for (int i = 0; s && i < m->n; i++) AP_CHECK(isfinite(ap_sim_q(s)[i]));
    ap_sim_free(s);
    ap_model_free(m);
  }
  AP_CHECK_NEAR(t_stop[1], t_stop[0], 1e-6);
}

int main(void) {
  test_fd_wheels();
  test_broken_gamma();
  test_flat();
  test_two_forms();
  printf("a disk released 0.5 rad from upright falls flat:\n");
  test_falls_flat();
  return ap_check_finish("test_wheels");
}
