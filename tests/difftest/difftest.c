/* The differential tester (docs/testing.md): random valid models from consecutive seeds, each
 * run in every mode, path and stepper and compared (compare.c); a model that disagrees is
 * shrunk (bodies, constraints, effects, initial states, the ground's motion dropped and t_end
 * halved while it still disagrees) and written as a regression scene.
 *
 *   difftest [--models N] [--seed S] [--save DIR] [--quiet]   random models S, S+1, ...
 *            [--no-shrink] [--print]   (report as found; --save then writes them unshrunk)
 *            [--contacts]              (some rolling contacts get contact modes)
 *            [--compiled]              (each model also compiled, compared with the
 *                                      interpreted run: compiled.c; exit 77 without a
 *                                      C compiler)
 *                                      (print each model's scene, run nothing)
 *   difftest SCENE|DIR ...                                     scenes (every *.yaml of a DIR)
 *
 * APPELL_DIFFTEST_MODELS, when set, replaces N (fewer models under the sanitizers). Exit
 * status 1 when any model disagrees, 2 for bad arguments. The last line is the summary:
 * models, agreeing, refused (by every mode alike), stopped (the reference too), disagreeing,
 * simulations, and the largest difference found as a fraction of its bound. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "compare.h"
#include "compiled.h"
#include "gen.h"

enum { TEXT_LEN = 32768 };

typedef struct tally {
  long models, count[4], runs;
  double worst, worst_by[DT_NCHECK];
  char worst_what[200];
} tally;

static void add(tally *t, const dt_result *r, const char *name) {
  t->models++, t->count[r->verdict]++, t->runs += r->runs;
  for (int i = 0; i < DT_NCHECK && r->verdict != DT_DISAGREE; i++)
    t->worst_by[i] = fmax(t->worst_by[i], r->worst_by[i]);
  if (r->worst > t->worst && r->verdict != DT_DISAGREE) {
    t->worst = r->worst;
    snprintf(t->worst_what, sizeof t->worst_what, "%s: %s", name, r->worst_what);
  }
}

/* The largest difference / bound of the agreeing models, per kind of check. */
static void print_worst_by(const tally *t) {
  printf("difftest: largest difference / bound by check:");
  for (int i = 0; i < DT_NCHECK; i++)
    printf("%s %s %.3g", i ? "," : "", dt_check_names[i], t->worst_by[i]);
  printf("\n");
}

static int compiled_too;   /* --compiled */
static dt_ctally ctally;

/* dt_check, and with --compiled the compiled model against the interpreted one. */
static void check_model(const char *text, const dt_opts *o, dt_result *r, int count) {
  dt_check(text, o, r);
  if (!compiled_too) return;
  dt_cresult c;
  dt_check_compiled(text, o, &c);
  dt_compiled_merge(&c, r);
  if (count) dt_compiled_add(&ctally, &c);
}

static int fails(const dt_model *m, const dt_opts *o, char *text) {
  dt_result r;
  dt_write(m, NULL, text, TEXT_LEN);
  check_model(text, o, &r, 0);
  return r.verdict == DT_DISAGREE;
}

/* Try one simplification; keep it when the model still disagrees. */
static int try_keep(dt_model *m, const dt_model *cand, const dt_opts *o, char *text) {
  if (!fails(cand, o, text)) return 0;
  *m = *cand;
  return 1;
}

static void shrink(dt_model *m, const dt_opts *o, char *text) {
  dt_model *c = malloc(sizeof *c);
  for (int changed = 1; changed;) {
    changed = 0;
    for (int i = m->nb - 1; i >= 0; i--)
      if (m->b[i].live && dt_live_bodies(m) > 1) {
        *c = *m, dt_drop_body(c, i);
        changed |= try_keep(m, c, o, text);
      }
    for (int i = 0; i < m->nc; i++)
      if (m->c[i].live) *c = *m, c->c[i].live = 0, changed |= try_keep(m, c, o, text);
    for (int i = 0; i < m->ne; i++)
      if (m->e[i].live) *c = *m, c->e[i].live = 0, changed |= try_keep(m, c, o, text);
    for (int i = 0; i < m->nb; i++)
      if (m->b[i].live && m->b[i].init[0]) *c = *m, c->b[i].init[0] = 0,
                                           changed |= try_keep(m, c, o, text);
    if (m->ground[0]) *c = *m, c->ground[0] = 0, changed |= try_keep(m, c, o, text);
    if (m->t_end > 0.06) *c = *m, c->t_end = m->t_end / 2, changed |= try_keep(m, c, o, text);
  }
  free(c);
}

static void save(const char *dir, const dt_model *m, const dt_result *r, char *text) {
  char header[2600], path[512];
  snprintf(header, sizeof header, "A disagreement of the modes found by tests/difftest (seed "
           "%llu), shrunk:\n%s", (unsigned long long)m->seed, r->what);
  size_t h = strlen(header);
  while (h > 0 && header[h - 1] == '\n') header[--h] = 0;
  dt_write(m, header, text, TEXT_LEN);
  snprintf(path, sizeof path, "%s/seed_%llu.yaml", dir, (unsigned long long)m->seed);
  FILE *f = fopen(path, "w");
  if (!f || fputs(text, f) < 0 || fclose(f)) fprintf(stderr, "difftest: cannot write %s\n", path);
  else printf("  saved %s\n", path);
}

static int print_only;  /* --print: write each model's scene to stdout, run nothing */
static int no_shrink;   /* --no-shrink: report disagreements as found (recheck a campaign's seeds) */

static int random_models(long models, unsigned long long seed, const char *dir, int quiet) {
  dt_opts o = dt_opts_default();
  tally t = {0};
  char *text = malloc(TEXT_LEN);
  dt_model *m = malloc(sizeof *m);
  clock_t c0 = clock();
  for (long i = 0; i < models; i++) {
    dt_result r;
    dt_generate(seed + (unsigned long long)i, m);
    dt_write(m, NULL, text, TEXT_LEN);
    if (print_only) {
      printf("--- seed %llu\n%s", (unsigned long long)m->seed, text);
      continue;
    }
    o.expect_tree = m->expect_tree;
    check_model(text, &o, &r, 1);
    char name[32];
    snprintf(name, sizeof name, "seed %llu", seed + (unsigned long long)i);
    add(&t, &r, name);
    if (!quiet || r.verdict == DT_DISAGREE)
      printf("%s: %s (%d runs, worst %.2g %s)\n%s", name,
             (const char *[]){"agree", "refused", "stopped", "DISAGREE"}[r.verdict], r.runs,
             r.worst, r.worst_what, r.verdict == DT_AGREE ? "" : r.what);
    if (r.verdict == DT_DISAGREE && !no_shrink) {
      o.expect_tree = -1;
      shrink(m, &o, text);
      check_model((dt_write(m, NULL, text, TEXT_LEN), text), &o, &r, 0);
      printf("  shrunk to %d bodies:\n%s", dt_live_bodies(m), r.what);
      if (dir) save(dir, m, &r, text);
    } else if (r.verdict == DT_DISAGREE && dir) {
      save(dir, m, &r, text);   /* --no-shrink: the model as generated */
    }
    if (quiet && (i + 1) % 500 == 0)
      printf("difftest: %ld models, %ld disagree, %.0f s\n", i + 1, t.count[DT_DISAGREE],
             (double)(clock() - c0) / CLOCKS_PER_SEC);
  }
  printf("difftest: %ld models from seed %llu: %ld agree, %ld refused, %ld stopped, %ld disagree; "
         "%ld simulations, %.1f s; largest difference %.3g of its bound (%s)\n", t.models, seed,
         t.count[0], t.count[1], t.count[2], t.count[3], t.runs,
         (double)(clock() - c0) / CLOCKS_PER_SEC, t.worst, t.worst_what);
  print_worst_by(&t);
  if (compiled_too) dt_compiled_print(&ctally);
  free(text), free(m);
  return t.count[DT_DISAGREE] > 0;
}

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  char *text = f ? calloc(TEXT_LEN, 1) : NULL;
  if (text) fread(text, 1, TEXT_LEN - 1, f);
  if (f) fclose(f);
  return text;
}

static int one_scene(const char *path, tally *t) {
  char *text = read_text(path);
  if (!text) {
    fprintf(stderr, "difftest: cannot read %s\n", path);
    return 1;
  }
  dt_opts o = dt_opts_default();
  dt_result r;
  check_model(text, &o, &r, 1);
  add(t, &r, path);
  printf("%s: %s (%d runs, worst %.2g %s)\n%s", path,
         (const char *[]){"agree", "refused", "stopped", "DISAGREE"}[r.verdict], r.runs, r.worst,
         r.worst_what, r.verdict == DT_AGREE ? "" : r.what);
  /* a regression scene runs through in every mode, or is refused by every mode alike, or
   * (a motion that reaches a singular configuration) stops in every mode, the reference too */
  int expect = strstr(text, "\n# expect: refused\n")   ? DT_REFUSED
               : strstr(text, "\n# expect: stopped\n") ? DT_STOPPED
                                                        : DT_AGREE;
  free(text);
  return r.verdict != expect;
}

static int scenes(int argc, char **argv) {
  tally t = {0};
  int bad = 0;
  for (int a = 0; a < argc; a++) {
    DIR *d = opendir(argv[a]);
    if (!d) {
      bad |= one_scene(argv[a], &t);
      continue;
    }
    struct dirent *e;
    while ((e = readdir(d))) {
      size_t l = strlen(e->d_name);
      char path[1024];
      if (l < 6 || strcmp(e->d_name + l - 5, ".yaml")) continue;
      snprintf(path, sizeof path, "%s/%s", argv[a], e->d_name);
      bad |= one_scene(path, &t);
    }
    closedir(d);
  }
  printf("difftest: %ld scenes: %ld agree, %ld refused, %ld stopped, %ld disagree; %ld "
         "simulations\n", t.models, t.count[0], t.count[1], t.count[2], t.count[3], t.runs);
  print_worst_by(&t);
  if (compiled_too) dt_compiled_print(&ctally);
  return bad;
}

int main(int argc, char **argv) {
  long models = 200;
  unsigned long long seed = 1;
  const char *dir = NULL;
  int quiet = 0, a = 1;
  for (; a < argc && !strncmp(argv[a], "--", 2); a++) {
    if (!strcmp(argv[a], "--quiet")) quiet = 1;
    else if (!strcmp(argv[a], "--no-shrink")) no_shrink = 1;
    else if (!strcmp(argv[a], "--print")) print_only = 1;
    else if (!strcmp(argv[a], "--contacts")) dt_gen_contacts = 1;
    else if (!strcmp(argv[a], "--compiled")) compiled_too = 1;
    else if (a + 1 < argc && !strcmp(argv[a], "--models")) models = atol(argv[++a]);
    else if (a + 1 < argc && !strcmp(argv[a], "--seed")) seed = strtoull(argv[++a], NULL, 10);
    else if (a + 1 < argc && !strcmp(argv[a], "--save")) dir = argv[++a];
    else {
      fprintf(stderr, "usage: difftest [--models N] [--seed S] [--save DIR] [--quiet] "
              "[--no-shrink] [--print] [--contacts] [--compiled] | "
              "difftest SCENE|DIR ...\n");
      return 2;
    }
  }
  setvbuf(stdout, NULL, _IOLBF, 0);
  char why[600];
  if (compiled_too && !print_only && !dt_compiler_works(why, sizeof why)) {
    printf("difftest: --compiled skipped: no model can be compiled here (%s)\n", why);
    return 77;   /* meson's skip code */
  }
  if (a < argc) return scenes(argc - a, argv + a);
  const char *env = getenv("APPELL_DIFFTEST_MODELS");
  if (env && *env) models = atol(env);
  return random_models(models, seed, dir, quiet);
}
