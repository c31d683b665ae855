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
 * contact row .z, held by projection after each step). Both describe the same motion; over 5 s
 * at rtol 1e-12 their centres agree to ~1e-11 m (the integrators' error, not a modelling
 * difference: at rtol 1e-10 the difference grows about 100-fold). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

int main(void) {
  test_fd_wheels();
  test_broken_gamma();
  test_flat();
  return ap_check_finish("test_wheels");
}
