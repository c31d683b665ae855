/* appell check: validate a scene and print its structure (docs/cli.md).
 *
 * Prints the sizes of the compiled model (coordinates n, speeds k, constraint rows b), the rank
 * of A and the free speeds l at the initial state (pivoted QR, ap_partition), the redundant
 * rows the core names there, the bodies, joints, constraints, effects and output columns, the
 * simulation settings, and what the initial state needed to become consistent. Exit 0 when
 * the scene is good, 2 when it is not (the message names file:line:column and key path). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "cli.h"

static const char help[] =
    "usage: appell check SCENE [--set PATH=VALUE]...\n"
    "\n"
    "Validate SCENE and print its structure: coordinates n, speeds k, constraint rows b, the\n"
    "rank of the constraint matrix and the free speeds l at the initial state, redundant\n"
    "constraints, bodies, joints, effects, output columns and simulation settings.\n"
    "\n"
    "options:\n"
    "  --set PATH=VALUE   override a scalar of the scene (as for appell run)\n"
    "  -h, --help         this help\n"
    "\n"
    "Exit codes: 0 the scene is good, 2 bad input, 1 internal error.\n";

static void list_names(const char *title, int count, const char *(*name)(const ap_model *, int),
                       const ap_model *m) {
  printf("%s:", title);
  for (int i = 0; i < count; i++) printf(" %s", name(m, i));
  printf("%s\n", count ? "" : " none");
}

static void list_section(const ap_scene *sc, ap_scene_section sec, const char *title) {
  int n = ap_scene_count(sc, sec);
  printf("%-12s %d%s", title, n, n ? ":" : "");
  for (int i = 0; i < n; i++)
    printf(" %s (%s)%s", ap_scene_element_name(sc, sec, i), ap_scene_element_kind(sc, sec, i),
           i + 1 < n ? "," : "");
  printf("\n");
}

/* The normal load of every rolling contact at the initial state, and whether it is unique
 * (ap_contact_force.load). */
static void loads(const ap_scene *sc, ap_data *d) {
  const ap_model *m = ap_scene_model(sc);
  int nc = ap_scene_count(sc, AP_SCENE_CONSTRAINTS), shown = 0, worst = AP_LOAD_UNIQUE, count = 0;
  d->speeds_from_e = 0;
  d->want_reactions = 1;
  if (!ap_model_is_body_model(m) || ap_forward(m, d) != AP_OK) return;
  for (int i = 0; i < nc; i++) {
    ap_contact_force f;
    if (strcmp(ap_scene_element_kind(sc, AP_SCENE_CONSTRAINTS, i), "rolling") != 0 ||
        ap_body_contact_force(m, d, NULL, i, &f) != AP_OK)
      continue;
    printf("%s %s %.6g N", shown++ ? "," : "loads       ",
           ap_scene_element_name(sc, AP_SCENE_CONSTRAINTS, i), f.normal);
    if ((int)f.load > worst) worst = (int)f.load, count = f.ncontacts;
  }
  if (!shown) return;
  if (worst == AP_LOAD_MIN_NORM)
    printf("\n             statically indeterminate: %d rigid contacts under one chassis share its "
           "weight in many ways; these are the minimum-norm loads (a suspension, a prismatic "
           "joint with a spring per wheel, makes them unique: docs/vehicles.md)\n", count);
  else if (worst == AP_LOAD_JOINT)
    printf("\n             %d contacts on a line under a planar chassis: the chassis joint keeps "
           "the tilting moment about their line (a real robot needs a third contact)\n", count);
  else
    printf(" (unique)\n");
}

/* Rank, free speeds and redundant rows at the initial state. */
static int structure(const ap_scene *sc, const double *q0, const ap_scene_run *run) {
  const ap_model *m = ap_scene_model(sc);
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) return fprintf(stderr, "appell check: out of memory\n"), 1;
  d->t = run->t0;
  memcpy(d->q, q0, sizeof(double) * (size_t)ap_model_n(m));
  d->basis = AP_BASIS_PARTITIONED;
  d->rank_rtol = run->sim.rank_rtol;
  int rc = ap_partition(m, d);
  if (rc != AP_OK) {
    fprintf(stderr, "appell check: the constraints at the initial state: %s: %s\n",
            ap_strerror(rc), d->msg);
    ap_data_free(d);
    return cli_exit_code(rc);
  }
  printf("rank of A    %d (at t0 = %g)\n", d->rank, run->t0);
  printf("free speeds  l = %d\n", d->l);
  printf("redundant    %s\n", d->rank < ap_model_b(m) ? d->msg : "none");
  memcpy(d->v, q0 + ap_model_n(m), sizeof(double) * (size_t)ap_model_k(m));
  loads(sc, d);
  ap_data_free(d);
  return EXIT_OK;
}

static void settings(const ap_scene *sc, const ap_scene_run *r) {
  static const char *const modes[] = {"minimal", "projected", "dae", "plain"};
  printf("simulation   mode %s, method %s, rtol %g, atol %g, t0 %g, t_end %g\n",
         modes[r->sim.mode % 4], r->sim.method, r->sim.rtol, r->sim.atol, r->t0, r->t_end);
  printf("outputs      every %g s:", r->interval);
  for (int i = 0; i < ap_scene_count(sc, AP_SCENE_CHANNELS); i++)
    printf(" %s", ap_scene_element_name(sc, AP_SCENE_CHANNELS, i));
  printf("\n");
  printf("columns      %d:", ap_scene_output_count(sc));
  for (int i = 0; i < ap_scene_output_count(sc); i++) printf(" %s", ap_scene_output_name(sc, i));
  printf("\n");
}

/* parameters   3: w = 1.02, c = 0.08, lambda = 0.314159 (as evaluated, after --set) */
static void list_parameters(const ap_scene *sc) {
  int np = ap_scene_parameter_count(sc);
  if (np == 0) return;
  printf("parameters   %d:", np);
  for (int i = 0; i < np; i++) {
    const char *name = NULL;
    double value = 0.0;
    if (ap_scene_parameter(sc, i, &name, &value) == AP_OK)
      printf("%s %s = %.10g", i ? "," : "", name, value);
  }
  printf("\n");
}

static int report(ap_scene *sc, const char *file) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m), b = ap_model_b(m);
  char msg[1024], rep[2048];
  double *q0 = calloc((size_t)(n + k) + 1, sizeof *q0);
  if (!q0) return fprintf(stderr, "appell check: out of memory\n"), EXIT_INTERNAL;
  int rc = ap_scene_initial_state(sc, q0, q0 + n, rep, sizeof rep, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    free(q0);
    return cli_exit_code(rc);
  }
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  printf("scene        %s (%s)\n", ap_scene_name(sc), file);
  list_parameters(sc);
  list_section(sc, AP_SCENE_BODIES, "bodies");
  list_section(sc, AP_SCENE_JOINTS, "joints");
  printf("n = %-8d ", n), list_names("coordinates", n, ap_model_coord_name, m);
  printf("k = %-8d ", k), list_names("speeds", k, ap_model_speed_name, m);
  printf("b = %-8d ", b), list_names("constraint rows", b, ap_model_constraint_name, m);
  list_section(sc, AP_SCENE_CONSTRAINTS, "constraints");
  int code = structure(sc, q0, &run);
  list_section(sc, AP_SCENE_EFFECTS, "effects");
  settings(sc, &run);
  printf("initial      %s", rep[0] ? rep : "consistent as given\n");
  printf("energy       %s\n", ap_scene_conserves_energy(sc) ? "conserved" : "not conserved "
         "(drivers, damping, applied forces, a moving ground, contacts that slide or touch down)");
  free(q0);
  return code;
}

/* The linearize: section as appell linearize reads it: the operating-point guess (its
 * initial: and speed: loaded as overrides) and a linearizer of it, which checks the names in
 * free:, independent: and inputs: (nothing is linearized). */
static int check_linearize(const char *scene, const char *const *sets, int nsets) {
  char msg[1024];
  ap_scene_lin_guess g;
  int rc = ap_scene_lin_guess_load(scene, NULL, 0, sets, nsets, &g, msg, sizeof msg);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), cli_exit_code(rc);
  if (!g.sec.present) return ap_scene_lin_guess_free(&g), EXIT_OK;
  ap_lin_def def = ap_scene_lin_def(&g);
  ap_lin *L = NULL;
  rc = ap_scene_lin_create(&g, &def, &L);
  if (rc != AP_OK) fprintf(stderr, "appell check: %s\n", L ? ap_lin_message(L) : ap_strerror(rc));
  else printf("linearize    section good: about %s%s\n",
              def.about == AP_LIN_EQUILIBRIUM ? "an equilibrium" : "a steady motion",
              g.sec.nspeed ? ", with a speed parameter" : "");
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
  return cli_exit_code(rc);
}

int cmd_check(int argc, char **argv) {
  static const char *const known[] = {"--set", "--help", NULL};
  const char *scene = NULL, *sets[256];
  int nsets = 0;
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0)
      return fputs(help, stdout), EXIT_OK;
    if ((r = cli_opt(argc, argv, &i, "--set", &v)) != 0) {
      if (r < 0) return cli_need("check", "--set", "PATH=VALUE"), EXIT_INPUT;
      if (nsets >= 256) return fprintf(stderr, "appell check: at most 256 --set\n"), EXIT_INPUT;
      sets[nsets++] = v;
    } else if (argv[i][0] == '-' && argv[i][1]) {
      return cli_unknown("check", argv[i], known);
    } else if (!scene) {
      scene = argv[i];
    } else {
      return fprintf(stderr, "appell check: one scene at a time\n"), EXIT_INPUT;
    }
  }
  if (!scene) return fprintf(stderr, "appell check: no scene file (see --help)\n"), EXIT_INPUT;
  char msg[1024];
  ap_scene *sc = NULL;
  int st = ap_scene_load(scene, sets, nsets, &sc, msg, sizeof msg);
  if (st != AP_OK) return fprintf(stderr, "%s\n", msg), cli_exit_code(st);
  int code = report(sc, scene);
  ap_scene_free(sc);
  return code == EXIT_OK ? check_linearize(scene, sets, nsets) : code;
}
