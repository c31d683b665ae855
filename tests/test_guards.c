/* The layout tables and guard words of lib/core/arena.h (issue 24: an overrun inside one
 * allocation, the identity N written past its end into A, a0 and B, passed every sanitizer).
 *
 * Every build: the checker itself on hand-made tables - offsets follow from the counts, a
 * table whose offsets overlap, whose last array ends past the block or whose total is not the
 * sum is refused naming the array; a write one element past an array (and one inside the
 * guard's last word) is found and named, a write inside an array is not; every data layout of
 * the test scenes (dense and tree path) passes ap_data_create's check.
 * Guard build (meson -Dguards=true, AP_GUARDS; the sanitizer build of scripts/test): a write
 * one past d->N, past d->q of a tree-path data, past d->perm (the int block) and past the
 * joints' section of a body model's scratch, and past each inner array of lib/linalg's tree
 * work areas, makes the next stage return AP_ERR_INTERNAL with a message naming the array and
 * the stage. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "clitest.h"
#include "core/arena.h"
#include "core/core.h"
#include "core/structured.h"
#include "model/tree_model.h"

static void table_checks(void) {
  ap_arena a;
  char msg[512] = "";
  ap_arena_init(&a, "test block", sizeof(double), AP_ARENA_GUARD);
  AP_CHECK_EQ_INT(ap_arena_add(&a, "x", 5), 0);
  AP_CHECK_EQ_INT(ap_arena_add(&a, "y", 0), 1);
  AP_CHECK_EQ_INT(ap_arena_add(&a, "z", 7), 2);
  AP_CHECK_EQ_INT(a.e[1].offset, 5 + AP_ARENA_GUARD);
  AP_CHECK_EQ_INT(a.e[2].offset, 5 + 2 * AP_ARENA_GUARD);
  AP_CHECK_EQ_INT(a.total, 12 + 3 * AP_ARENA_GUARD);
  AP_CHECK_EQ_INT(ap_arena_check(&a, msg, sizeof msg), 0);
  ap_arena bad = a;
  bad.e[2].offset -= 1;   /* z starts inside y's guard */
  AP_CHECK_EQ_INT(ap_arena_check(&bad, msg, sizeof msg), -1);
  AP_CHECK(strstr(msg, "'z'") && strstr(msg, "overlaps"));
  printf("overlap: %s\n", msg);
  bad = a;
  bad.e[2].count += 1;    /* z's guard ends past the block */
  AP_CHECK_EQ_INT(ap_arena_check(&bad, msg, sizeof msg), -1);
  AP_CHECK(strstr(msg, "'z'") && strstr(msg, "past the block"));
  bad = a;
  bad.total += 3;         /* a size formula that disagrees with the arrays */
  AP_CHECK_EQ_INT(ap_arena_check(&bad, msg, sizeof msg), -1);
  AP_CHECK(strstr(msg, "sum to") != NULL);
  bad = a;
  bad.n = AP_ARENA_MAX + 1;
  AP_CHECK_EQ_INT(ap_arena_check(&bad, msg, sizeof msg), -1);
}

static void guard_checks(void) {
  ap_arena a;
  char msg[512] = "";
  ap_arena_init(&a, "test block", sizeof(double), AP_ARENA_GUARD);
  ap_arena_add(&a, "x", 5), ap_arena_add(&a, "y", 3), ap_arena_add(&a, "z", 4);
  double *blk = calloc(a.total, sizeof(double));
  ap_arena_fill_guards(&a, blk);
  AP_CHECK_EQ_INT(ap_arena_guard_hit(&a, blk, NULL), -1);
  double *x = blk + a.e[0].offset, *y = blk + a.e[1].offset, *z = blk + a.e[2].offset;
  for (int i = 0; i < 5; i++) x[i] = 1.0 + i;   /* writes inside the arrays */
  for (int i = 0; i < 3; i++) y[i] = NAN;
  z[3] = -INFINITY;
  AP_CHECK_EQ_INT(ap_arena_guard_hit(&a, blk, NULL), -1);
  AP_CHECK_EQ_INT(ap_arena_guard_msg(&a, blk, "s", msg, sizeof msg), 0);
  size_t word = 99;
  y[3] = 0.0;             /* one past y */
  AP_CHECK_EQ_INT(ap_arena_guard_hit(&a, blk, &word), 1);
  AP_CHECK_EQ_INT(word, 0);
  AP_CHECK_EQ_INT(ap_arena_guard_msg(&a, blk, "stage one", msg, sizeof msg), -1);
  AP_CHECK(strstr(msg, "'y'") && strstr(msg, "'stage one'") && strstr(msg, "test block"));
  printf("one past y: %s\n", msg);
  ap_arena_fill_guards(&a, blk);
  z[4 + AP_ARENA_GUARD - 1] = 2.0;   /* the last guard word of z, the block's last element */
  AP_CHECK_EQ_INT(ap_arena_guard_hit(&a, blk, &word), 2);
  AP_CHECK_EQ_INT(word, AP_ARENA_GUARD - 1);
  free(blk);
  /* ints: a guard of 16 ints is 8 words of the pattern */
  ap_arena_init(&a, "ints", sizeof(int), AP_ARENA_GUARD);
  ap_arena_add(&a, "p", 3), ap_arena_add(&a, "r", 2);
  AP_CHECK_EQ_INT(ap_arena_check(&a, msg, sizeof msg), 0);
  int *ib = calloc(a.total, sizeof(int));
  ap_arena_fill_guards(&a, ib);
  ib[a.e[0].offset + 3] = 7;
  AP_CHECK_EQ_INT(ap_arena_guard_hit(&a, ib, NULL), 0);
  free(ib);
}

static ap_scene *load(const char *file, const char *path) {
  char p[1200], set[64], msg[1024] = "";
  ct_source(p, sizeof p, "tests/scenes", file);
  snprintf(set, sizeof set, "simulation.path=%s", path);
  const char *sets[1] = {set};
  ap_scene *s = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(p, sets, 1, &s, msg, sizeof msg), AP_OK);
  if (!s) fprintf(stderr, "%s: %s\n", file, msg);
  return s;
}

/* A data of the scene's model at its initial state, partitioned and evaluated. */
static ap_data *data_at_start(ap_scene *s) {
  const ap_model *m = ap_scene_model(s);
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  if (!d) return NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(s, d->q, d->v, NULL, 0, NULL, 0), AP_OK);
  AP_CHECK_EQ_INT(ap_partition(m, d), AP_OK);
  AP_CHECK_EQ_INT(ap_forward(m, d), AP_OK);
  return d;
}

/* Write one element past an array of a fresh data, run the stage, expect the guard to name
 * the array (guard build) or nothing to happen to the stage (otherwise: the write lands in the
 * next array, which the stage rewrites). */
static void overrun(const char *file, const char *path, const char *array, int stage) {
  ap_scene *s = load(file, path);
  if (!s) return;
  const ap_model *m = ap_scene_model(s);
  ap_data *d = data_at_start(s);
  if (!d) {
    ap_scene_free(s);
    return;
  }
  int n = d->n, k = d->k;
  if (!strcmp(array, "d->N")) d->N[(size_t)n * k] = 0.5;
  else if (!strcmp(array, "d->q")) d->q[n] = 0.5;
  else if (!strcmp(array, "d->perm")) d->perm[k] = -1;
  else if (!strcmp(array, "joints")) {   /* a section of the body model's scratch */
    const ap_arena *L = m->ev.layout;
    ((ap_scratch *)d->internal)->ev[L->e[1].offset + L->e[1].count] = 0.5;
  }
  int rc = stage == 0 ? ap_fwd_position(m, d) : ap_fwd_velocity(m, d);
  const char *sname = stage == 0 ? "'position'" : "'velocity'";
  char want[64];
  snprintf(want, sizeof want, "'%s'", array);
  if (AP_GUARDS) {
    AP_CHECK_EQ_INT(rc, AP_ERR_INTERNAL);
    AP_CHECK(strstr(d->msg, want) != NULL && strstr(d->msg, sname) != NULL);
    printf("%s, %s path, one past %s: %s\n", file, path, array, d->msg);
    /* the next stage reports it again, naming the stage it was first found after */
    AP_CHECK_EQ_INT(ap_fwd_acceleration(m, d), AP_ERR_INTERNAL);
    AP_CHECK(strstr(d->msg, sname) != NULL);
  } else {
    printf("%s, %s path, one past %s: guards off (meson -Dguards=true), stage status %d\n",
           file, path, array, rc);
  }
  ap_data_free(d);
  ap_scene_free(s);
}

/* The tree path's workspace (lib/model/tree_build.c: the shadow's scratch, the geometry, the
 * row and force vectors, lib/linalg's tree work; ints) and the complex-step data's evaluator
 * scratch (lib/core/data_cs.c: the body model's sections in complex elements): one element
 * written past an array (ws->x, the last double before the tree work; the joints' section)
 * makes the next stage fail naming it in the guard build. */
static void overrun_ws_cs(void) {
  ap_scene *s = load("modes_chain.yaml", "tree");
  if (s) {
    const ap_model *m = ap_scene_model(s);
    ap_data *d = data_at_start(s);
    ap_st *st = d ? ((ap_scratch *)d->internal)->st : NULL;
    AP_CHECK(st != NULL);
    if (st) {
      ap_tree_ws *ws = st->ws;
      ws->x[ws->P->T.k] = 0.5;   /* one past ws->x (k doubles) */
      int rc = ap_fwd_position(m, d);
      if (AP_GUARDS) {
        AP_CHECK_EQ_INT(rc, AP_ERR_INTERNAL);
        AP_CHECK(strstr(d->msg, "'ws->x'") && strstr(d->msg, "tree workspace doubles"));
        printf("modes_chain.yaml, tree workspace, one past ws->x: %s\n", d->msg);
      } else {
        printf("tree workspace, one past ws->x: guards off, stage status %d\n", rc);
      }
    }
    ap_data_free(d);
    ap_scene_free(s);
  }
  s = load("modes_chain.yaml", "dense");
  if (!s) return;
  const ap_model *m = ap_scene_model(s);
  ap_data_cs *dc = NULL;
  AP_CHECK_EQ_INT(ap_data_create_cs(m, &dc), AP_OK);
  ap_data *d = data_at_start(s);
  if (dc && d) {
    for (int i = 0; i < d->n; i++) dc->q[i] = d->q[i];
    for (int i = 0; i < d->k; i++) dc->v[i] = d->v[i];
    AP_CHECK_EQ_INT(ap_fwd_position_cs(m, dc), AP_OK);   /* clean: every guard intact */
    const ap_arena *L = m->ev.layout;
    ((ap_scratch_cs *)dc->internal)->ev[L->e[1].offset + L->e[1].count] = 0.5;
    int rc = ap_fwd_position_cs(m, dc);
    if (AP_GUARDS) {
      AP_CHECK_EQ_INT(rc, AP_ERR_INTERNAL);
      AP_CHECK(strstr(dc->msg, L->e[1].name) != NULL && strstr(dc->msg, "'position'") != NULL);
      printf("modes_chain.yaml, complex-step data, one past %s: %s\n", L->e[1].name, dc->msg);
    } else {
      printf("complex-step scratch, one past %s: guards off, stage status %d\n", L->e[1].name,
             rc);
    }
  }
  ap_data_free_cs(dc);
  ap_data_free(d);
  ap_scene_free(s);
}

/* lib/linalg's work areas inside the tree workspace (ap_la_tree_work, and ap_la_comp_work in
 * component mode) are laid out array by array with guards between their inner arrays: in the
 * guard build, one element written past any inner array of a fresh data makes the next
 * position stage fail naming that array ("ap_la_tree_work.F") and the stage. Without guards
 * nothing is written (past the last inner array lies the next block). */
static void overrun_tree_work(const char *file) {
  ap_scene *s = load(file, "tree");
  if (!s) return;
  const ap_model *m = ap_scene_model(s);
  int narr = 0, caught = 0;
  for (int a = 0;; a++) {
    ap_data *d = data_at_start(s);
    ap_st *st = d ? ((ap_scratch *)d->internal)->st : NULL;
    AP_CHECK(st != NULL);
    if (!st) {
      ap_data_free(d);
      break;
    }
    ap_tree_ws *ws = st->ws;
    ap_la_work_array la[2 * AP_LA_WORK_ARRAYS_MAX];
    int n = ws->P->comp ? ap_la_comp_work_arrays(&ws->P->T, &ws->CW, la) : 0;
    n += ap_la_tree_work_arrays(&ws->P->T, ws->P->lmax, &ws->W, la + n);
    narr = n;
    if (a >= n || !AP_GUARDS) {
      ap_data_free(d);
      break;
    }
    if (la[a].dptr) (*la[a].dptr)[la[a].count] = 0.5;   /* one past the inner array */
    else (*la[a].iptr)[la[a].count] = -7;
    int rc = ap_fwd_position(m, d);
    char want[96];
    snprintf(want, sizeof want, "'%s'", la[a].name);
    int named = rc == AP_ERR_INTERNAL && strstr(d->msg, want) && strstr(d->msg, "'position'");
    AP_CHECK(named);
    caught += named;
    if (a == 0 || !named) printf("%s, one past %s: %s\n", file, la[a].name, d->msg);
    ap_data_free(d);
  }
  if (AP_GUARDS) {
    printf("%s, tree path: one past each of lib/linalg's %d inner work arrays: %d caught and "
           "named\n", file, narr, caught);
    AP_CHECK(narr >= 27 && caught == narr);
  } else {
    printf("%s, lib/linalg's %d inner work arrays: guards off\n", file, narr);
  }
  ap_scene_free(s);
}

/* Every data layout of the regression scenes passes ap_data_create's check, and in the guard
 * build a whole run leaves every guard intact (the run would fail with AP_ERR_INTERNAL). */
static void clean_layouts(void) {
  const char *files[3] = {"modes_double_top.yaml", "modes_chain.yaml", "modes_free_balls.yaml"};
  for (int f = 0; f < 3; f++)
    for (int p = 0; p < 2; p++) {
      ap_scene *s = load(files[f], p ? "tree" : "dense");
      if (!s) continue;
      ap_data *d = data_at_start(s);
      ap_data_free(d);
      ap_scene_free(s);
    }
}

int main(void) {
  ct_find_source(ct_src, sizeof ct_src);
  table_checks();
  guard_checks();
  clean_layouts();
  overrun("modes_double_top.yaml", "dense", "d->N", 0);
  overrun("modes_chain.yaml", "tree", "d->q", 1);
  overrun("modes_free_balls.yaml", "dense", "d->perm", 0);
  overrun("modes_chain.yaml", "dense", "joints", 1);
  overrun_ws_cs();
  overrun_tree_work("modes_chain.yaml");
  printf("guard build: %s\n", AP_GUARDS ? "yes" : "no");
  return ap_check_finish("guards");
}
