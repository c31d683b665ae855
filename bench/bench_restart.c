/* bench_restart: what re-partitioning costs the steppers in minimal mode. A knife edge turns
 * twice per revolution through the angle where its dependent speed must change, so minimal
 * mode switches partitions (a change of coordinates on the same trajectory) about twice per
 * turn and continues the stepper from the new coordinates (ap_step_restart). Counted, not
 * timed: steps, right-hand-side evaluations, error-test failures, partition switches, stepper
 * restarts, position stages beyond the evaluations' own per step (d->cnt.position minus the
 * evaluations: the driver's second position stage after a step, the re-partitions') and the
 * error.
 *
 * Cases (rtol = atol = 1e-4 ... 1e-12, outputs at 10 equally spaced times):
 *   knife_edge  the refsys knife edge of bench_wp (k 3, b 1; m 2, J 0.3, slope 0.4, w 2 rad/s,
 *               10 s: about 3 turns); error: contact point against the closed form (m)
 *   knife_spin  the spinning knife of tests/test_reference.c (w 20 rad/s, 20 s: 64 turns)
 *   skate       examples/scenes/skate_incline.yaml (a body model: planar joint + knife-edge
 *               constraint) with heading_rate 20 rad/s over 20 s; error: (x, y, heading)
 *               against the same scene with fehlberg8 at rtol 1e-13 (dop853 agrees to 1e-11)
 *
 * Usage: bench_restart [--csv FILE] [--methods a,b] [--scene PATH]
 *        (run from the source root, or give the scene's path). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "refsys.h"

#define NOUT 10

typedef struct bcase {
  const char *name;
  const ap_model *m;
  double q0[8], v0[8], T;
  rs_knife kp;            /* closed form (refsys cases) */
  int exact;              /* 1: closed form; 0: the reference positions below */
  double ref[NOUT][3];
} bcase;

typedef struct bres {
  int status;
  double err;
  ap_sim_stats st;
  long positions;
  char msg[160];
} bres;

static void run(const bcase *c, const char *method, double tol, bres *r) {
  ap_sim_def sd = ap_sim_def_default();
  sd.method = method, sd.rtol = sd.atol = tol;
  ap_sim *s = NULL;
  memset(r, 0, sizeof *r);
  r->status = ap_sim_create(c->m, &sd, 0.0, c->q0, c->v0, &s, r->msg, sizeof r->msg);
  if (r->status != AP_OK) return;
  long pos0 = ap_sim_data(s)->cnt.position;
  for (int i = 0; i < NOUT && r->status == AP_OK; i++) {
    double t = c->T * (i + 1) / NOUT, qe[3];
    r->status = ap_sim_advance(s, t);
    if (r->status != AP_OK) {
      snprintf(r->msg, sizeof r->msg, "%s", ap_sim_message(s));
      break;
    }
    const double *q = ap_sim_q(s);
    if (c->exact) rs_knife_exact(&c->kp, c->q0, c->v0, t, qe, NULL, NULL);
    else memcpy(qe, c->ref[i], sizeof qe);
    for (int j = 0; j < (c->exact ? 2 : 3); j++) r->err = fmax(r->err, fabs(q[j] - qe[j]));
  }
  ap_sim_get_stats(s, &r->st);
  /* minus the evaluations' own and the full evaluation ending each ap_sim_advance */
  r->positions = ap_sim_data(s)->cnt.position - pos0 - NOUT - r->st.rhs_evals;
  ap_sim_free(s);
}

static ap_model *knife_model(bcase *c, rs_knife kp, double phi0, double u0, double w0,
                             double T) {
  ap_system_def def;
  ap_model *m = NULL;
  c->kp = kp, c->T = T, c->exact = 1;
  rs_knife_system(&c->kp, &def);
  rs_knife_initial(0.0, 0.0, phi0, u0, w0, c->q0, c->v0);
  if (ap_model_from_system(&def, &m, NULL, 0) != AP_OK) {
    fprintf(stderr, "bench_restart: %s: model\n", c->name);
    exit(1);
  }
  c->m = m;
  return m;
}

/* The skate scene spinning at 20 rad/s; its reference from a tight run. */
static ap_scene *skate_case(bcase *c, const char *path) {
  static const char *const sets[] = {"initial.skate.heading_rate=20"};
  char msg[512], rep[512];
  ap_scene *sc = NULL;
  if (ap_scene_load(path, sets, 1, &sc, msg, sizeof msg) != AP_OK ||
      ap_scene_initial_state(sc, c->q0, c->v0, rep, sizeof rep, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "bench_restart: %s: %s\n", path, msg);
    exit(1);
  }
  c->m = ap_scene_model(sc), c->T = 20.0, c->exact = 0;
  ap_method_info info;
  const char *check = ap_method_find("dop853", &info) == AP_OK ? "dop853" : "verner6";
  for (int pass = 0; pass < 2; pass++) {   /* reference, then its check with another method */
    ap_sim_def sd = ap_sim_def_default();
    sd.method = pass ? check : "fehlberg8", sd.rtol = 1e-13, sd.atol = 1e-13;
    ap_sim *s = NULL;
    double diff = 0.0;
    if (ap_sim_create(c->m, &sd, 0.0, c->q0, c->v0, &s, msg, sizeof msg) != AP_OK) {
      fprintf(stderr, "bench_restart: skate reference: %s\n", msg);
      exit(1);
    }
    for (int i = 0; i < NOUT; i++) {
      if (ap_sim_advance(s, c->T * (i + 1) / NOUT) != AP_OK) {
        fprintf(stderr, "bench_restart: skate reference: %s\n", ap_sim_message(s));
        exit(1);
      }
      for (int j = 0; j < 3; j++)
        if (pass) diff = fmax(diff, fabs(ap_sim_q(s)[j] - c->ref[i][j]));
        else c->ref[i][j] = ap_sim_q(s)[j];
    }
    if (pass) printf("skate reference (fehlberg8, 1e-13) against %s at 1e-13: %.1e\n", check, diff);
    ap_sim_free(s);
  }
  return sc;
}

static int listed(const char *list, const char *name) {
  if (!list) return 1;
  size_t n = strlen(name);
  for (const char *p = strstr(list, name); p; p = strstr(p + 1, name))
    if ((p == list || p[-1] == ',') && (p[n] == ',' || p[n] == '\0')) return 1;
  return 0;
}

int main(int argc, char **argv) {
  const char *csv = NULL, *list = NULL, *scene = "examples/scenes/skate_incline.yaml";
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--methods") && i + 1 < argc) list = argv[++i];
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else {
      fprintf(stderr, "usage: bench_restart [--csv FILE] [--methods a,b] [--scene PATH]\n");
      return 2;
    }
  }
  static bcase cases[3];
  cases[0].name = "knife_edge", cases[1].name = "knife_spin", cases[2].name = "skate";
  ap_model *m0 = knife_model(&cases[0], (rs_knife){2.0, 0.3, 9.81, 0.4}, 0.3, 1.0, 2.0, 10.0);
  ap_model *m1 = knife_model(&cases[1], (rs_knife){1.0, 0.1, 9.81, 0.2}, 0.1, 0.5, 20.0, 20.0);
  ap_scene *sc = skate_case(&cases[2], scene);
  static const char *const methods[] = {"dopri5", "verner6", "fehlberg8", "dop853", "adams"};
  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (out) fprintf(out, "case,method,tol,status,err,steps,rhs_evals,err_fails,rhs_fails,switches,"
                        "restarts,extra_positions_per_step\n");
  printf("%-10s %-9s %7s %9s %7s %8s %6s %6s %8s %8s %9s\n", "case", "method", "tol", "err",
         "steps", "evals", "fails", "rhs_f", "switches", "restarts", "+pos/step");
  for (int c = 0; c < 3; c++)
    for (int k = 0; k < 5; k++) {
      if (!listed(list, methods[k])) continue;
      for (int e = 4; e <= 12; e += 2) {
        bres r;
        run(&cases[c], methods[k], pow(10.0, -e), &r);
        double pps = r.st.steps ? (double)r.positions / r.st.steps : 0.0;
        printf("%-10s %-9s %7.0e %9.2e %7ld %8ld %6ld %6ld %8ld %8ld %9.3f%s%s\n",
               cases[c].name, methods[k], pow(10.0, -e), r.err, r.st.steps, r.st.rhs_evals,
               r.st.err_fails, r.st.rhs_fails, r.st.partition_switches, r.st.restarts, pps, r.status ? "  FAILED: " : "",
               r.status ? r.msg : "");
        if (out)
          fprintf(out, "%s,%s,%.0e,%d,%.4e,%ld,%ld,%ld,%ld,%ld,%ld,%.4f\n", cases[c].name,
                  methods[k], pow(10.0, -e), r.status, r.err, r.st.steps, r.st.rhs_evals,
                  r.st.err_fails, r.st.rhs_fails, r.st.partition_switches, r.st.restarts, pps);
      }
    }
  if (out) fclose(out);
  ap_model_free(m0), ap_model_free(m1), ap_scene_free(sc);
  return 0;
}
