/* The tree path's plan, built once from a compiled body model (tree_model.h, docs/large.md).
 *
 * Forest: tree body i is the child of joint i (topological order, so parent[i] < i); its free
 * speeds are the joint's; its rows are those of the constraints on the body (a prescribed
 * speed lives on the child of its joint, as a direct term on that speed). Trees are the
 * ground's subtrees: with rows on one body each, they are the independent components.
 * Shadow: a copy of the model's tables with k = 0 and K1 = 1 (its joints keep only the leading
 * speeds that may be driven, with no free index), laid out again by ap_kin_layout, so every
 * body block holds R, o, inertia, velocities, biases and one 3-column of each Jacobian.
 * Capacities: rows pushed from a body to its parent take slots; 2 b + 16 slots (each row may
 * climb about one level on average) and b + 1 rows at one body; one tree's free speeds at most
 * k_t - b_t + 6 (six redundant rows per tree). Beyond them the position stage reports
 * AP_ERR_UNSUPPORTED. */
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/con_kind.h"
#include "model/tree_model.h"

/* The body a constraint's rows live on, or -1 when the tree path cannot take the constraint
 * (its reason in why). */
static int con_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                    size_t len) {
  return c->kind->tree_body(m, M, c, why, len);
}

/* Local free column of global speed col in joint J, or -1. */
static int local_column(const ap_mjoint *J, int col) {
  for (int i = 0, f = 0; i < J->nv; i++) {
    if (J->vidx[i] < 0) continue;
    if (J->vidx[i] == col) return f;
    f++;
  }
  return -1;
}

static int *take(int **p, size_t n) {
  int *out = *p;
  *p += n;
  return out;
}

/* Forest arrays: parents, speeds, children (ascending), trees (bodies parents first), by
 * counting passes. */
static void forest(const ap_bmodel *M, ap_tplan *P, int *parent, int *fofs, int *fidx,
                   int *cofs, int *cidx, int *tofs, int *tbody, int *tree) {
  int nb = M->nj, f = 0, nt = 0;
  for (int i = 0; i < nb; i++) {
    const ap_mjoint *J = &M->joints[i];
    P->body[i] = J->child;
    parent[i] = J->parent >= 0 ? M->bodies[J->parent].joint : -1;
    fofs[i] = f;
    for (int a = 0; a < J->nv; a++)
      if (J->vidx[a] >= 0) fidx[f++] = J->vidx[a];
    P->T.maxnf = f - fofs[i] > P->T.maxnf ? f - fofs[i] : P->T.maxnf;
    tree[i] = parent[i] < 0 ? nt++ : tree[parent[i]];
  }
  fofs[nb] = f;
  memset(cofs, 0, sizeof(int) * (size_t)(nb + 1));
  memset(tofs, 0, sizeof(int) * (size_t)(nt + 1));
  for (int i = 0; i < nb; i++) {
    if (parent[i] >= 0) cofs[parent[i] + 1]++;
    tofs[tree[i] + 1]++;
  }
  for (int i = 0; i < nb; i++) cofs[i + 1] += cofs[i];
  for (int t = 0; t < nt; t++) tofs[t + 1] += tofs[t];
  int *cfill = P->kspeed, *tfill = P->kspeed + nb;   /* scratch: kspeed is filled later */
  for (int i = 0; i < nb; i++) cfill[i] = cofs[i];
  for (int t = 0; t < nt; t++) tfill[t] = tofs[t];
  for (int i = 0; i < nb; i++) {
    if (parent[i] >= 0) cidx[cfill[parent[i]]++] = i;
    tbody[tfill[tree[i]]++] = i;
  }
  P->T.ntree = nt;
}

/* Rows by body (own rows in constraint order), their direct terms, the row capacities and
 * the capacity of one tree's free speeds. Returns AP_ERR_UNSUPPORTED when a constraint cannot
 * be taken. */
static int rows(const ap_model *m, const ap_bmodel *M, ap_tplan *P, int *rofs, int *ridx,
                int *rdir, char *why, size_t len) {
  int nb = M->nj, *rb = P->kspeed;   /* scratch: tree body of each row, fill pointers */
  memset(rofs, 0, sizeof(int) * (size_t)(nb + 1));
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    int body = con_body(m, M, c, why, len);
    if (body < 0) return AP_ERR_UNSUPPORTED;
    for (int r = 0; r < c->nrows; r++) rb[c->row + r] = M->bodies[body].joint;
    rofs[M->bodies[body].joint + 1] += c->nrows;
  }
  for (int i = 0; i < nb; i++) rofs[i + 1] += rofs[i];
  int *fill = rb + M->b;
  for (int i = 0; i < nb; i++) fill[i] = rofs[i];
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    for (int r = 0; r < c->nrows; r++) {
      int i = rb[c->row + r], p = fill[i]++;
      ridx[p] = c->row + r, P->rcon[p] = ci, P->rrow[p] = r;
      rdir[p] = c->def.kind == AP_CON_PRESCRIBED_SPEED ? local_column(&M->joints[i], c->col) : -1;
    }
  }
  return AP_OK;
}

/* The shadow body model: no speeds, one twist column (module note). */
static int make_shadow(const ap_model *m, const ap_bmodel *M, ap_tplan *P) {
  P->sjoints = calloc((size_t)M->nj + 1, sizeof *P->sjoints);
  if (!P->sjoints) return AP_ERR_NOMEM;
  for (int j = 0; j < M->nj; j++) {
    ap_mjoint *J = &P->sjoints[j];
    *J = M->joints[j];
    int last = -1;
    for (int i = 0; i < J->ndrivable; i++)
      if (J->drive[i]) last = i;
    J->nv = last + 1;   /* the driven speeds keep their places; free ones add nothing */
    for (int i = 0; i < J->nv; i++) J->vidx[i] = -1;
  }
  P->M = M;
  P->shadow = *M;
  P->shadow.joints = P->sjoints;
  P->shadow.k = 0, P->shadow.K1 = 1, P->shadow.ncol = M->has_drive ? 1 : 0;
  P->shadow.max_user_rows = 0;
  ap_kin_layout(&P->shadow);
  memset(&P->sm, 0, sizeof P->sm);
  snprintf(P->sm.name, sizeof P->sm.name, "%s", m->name);
  P->sm.n = m->n, P->sm.k = m->k, P->sm.b = m->b;
  P->sm.coord_names = m->coord_names, P->sm.speed_names = m->speed_names;
  P->sm.constraint_names = m->constraint_names;
  P->sm.ev.impl = &P->shadow;
  P->sm.ops_impl = P;   /* with no ops: the shadow of this plan (evaluate.c's close_loops) */
  return AP_OK;
}

/* The workspace's doubles and ints, one table each X(field, count) in block order
 * (core/arena.h): the sizes (capacities) and the carving (ap_tree_ws_init) both come from it.
 * The last entries are lib/linalg's work areas, array by array (ap_la_comp_work_arrays, then
 * ap_la_tree_work_arrays: names "ap_la_tree_work.F", ...), so that in the guard build a guard
 * lies between every two of their inner arrays too. */
#define TREE_WS_DOUBLES(X)                                                                 \
  X(ws->S, P->shadow.scratch) X(ws->g.d, 3 * nb) X(ws->g.S, 6 * k) X(ws->g.M, 13 * nb)     \
  X(ws->g.C, 6 * b) X(ws->rho, 6 * nb) X(ws->U, 6 * nb) X(ws->F, 6 * nb) X(ws->x, k)       \
  X(ws->rb, b) X(ws->qn, n) X(ws->hp, nhd)
#define TREE_WS_INTS(X) X(ws->avoid, k) X(ws->tkeep, nt) X(ws->hip, nhi)

/* lib/linalg's arrays (into la, fields of ws->W and ws->CW), at most 2 AP_LA_WORK_ARRAYS_MAX. */
static int ws_la_arrays(const ap_tplan *P, ap_tree_ws *ws, ap_la_work_array *la) {
  int n = P->comp ? ap_la_comp_work_arrays(&P->T, &ws->CW, la) : 0;
  return n + ap_la_tree_work_arrays(&P->T, P->lmax, &ws->W, la + n);
}

#define WS_ADD(f_, c_) ap_arena_add(L, #f_, (c_));
static void ws_layout(const ap_tplan *P, ap_arena *Ld, ap_arena *Li, ap_la_work_array *la,
                      int nla) {
  size_t nb = (size_t)P->T.nb, k = (size_t)P->T.k, b = (size_t)P->T.b, nhi = 0;
  size_t nhd = ap_tree_hol_ws_size(P, &nhi), n = (size_t)P->M->n, nt = (size_t)P->T.ntree;
  ap_arena *L = Ld;
  ap_arena_init(L, "tree workspace doubles", sizeof(double), AP_ARENA_GUARDS);
  TREE_WS_DOUBLES(WS_ADD)
  L = Li;
  ap_arena_init(L, "tree workspace ints", sizeof(int), AP_ARENA_GUARDS);
  TREE_WS_INTS(WS_ADD)
  for (int j = 0; j < nla; j++) ap_arena_add(la[j].dptr ? Ld : Li, la[j].name, la[j].count);
}

/* The layout of a workspace of plan P (ws: the one whose fields la points into, or NULL). */
static int ws_tables(const ap_tplan *P, ap_tree_ws *ws, ap_arena *Ld, ap_arena *Li,
                     ap_la_work_array *la) {
  ap_tree_ws dummy;
  int nla = ws_la_arrays(P, ws ? ws : &dummy, la);
  ws_layout(P, Ld, Li, la, nla);
  return nla;
}

/* Capacities (module note) and the workspace sizes. */
static void capacities(const ap_bmodel *M, ap_tplan *P) {
  ap_la_tree *T = &P->T;
  int lmax = 1;
  for (int t = 0; t < T->ntree; t++) {
    int kt = 0, bt = 0;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
      int i = T->tbody[a];
      kt += T->fofs[i + 1] - T->fofs[i], bt += T->rofs[i + 1] - T->rofs[i];
    }
    int lt = kt - bt > 0 ? kt - bt + 6 : 6;
    lt = lt < kt ? lt : kt;
    lmax = lt > lmax ? lt : lmax;
  }
  P->lmax = lmax;
  int kmax = 0;   /* component mode: every tree small; its blocks hold all of a tree's speeds */
  for (int t = 0; t < T->ntree; t++) {
    int kt = 0;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++)
      kt += T->fofs[T->tbody[a] + 1] - T->fofs[T->tbody[a]];
    kmax = kt > kmax ? kt : kmax;
  }
  P->comp = kmax <= AP_TREE_COMP_K;
  if (P->comp) P->lmax = kmax > 1 ? kmax : 1;
  T->cap = 2 * M->b + 16, T->maxrow = M->b + 1;
  ap_arena Ld, Li;
  ap_la_work_array la[2 * AP_LA_WORK_ARRAYS_MAX];
  ws_tables(P, NULL, &Ld, &Li, la);
  P->nd = Ld.total, P->ni = Li.total;
  char why[256];
  if (ap_arena_check(&Ld, why, sizeof why) != 0 || ap_arena_check(&Li, why, sizeof why) != 0)
    P->nd = 0;   /* a table over AP_ARENA_MAX arrays: ap_tree_plan_create refuses the plan */
}

int ap_tree_plan_create(const ap_model *m, ap_tplan **out, char *why, size_t why_len) {
  *out = NULL;
  if (why && why_len) why[0] = '\0';
  if (!ap_model_is_body_model(m)) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(m);
  ap_tplan *P = calloc(1, sizeof *P);
  size_t nb = (size_t)M->nj, k = (size_t)M->k, b = (size_t)M->b;
  size_t nks = (k > b ? k : b) + 2 * nb + 2;   /* kspeed, also scratch for the passes */
  if (P) P->ints = calloc(9 * nb + 4 + k + 4 * b + nks, sizeof(int));
  if (!P || !P->ints) {
    free(P);
    return AP_ERR_NOMEM;
  }
  int *ip = P->ints;
  int *parent = take(&ip, nb), *fofs = take(&ip, nb + 1), *fidx = take(&ip, k);
  int *rofs = take(&ip, nb + 1), *ridx = take(&ip, b), *rdir = take(&ip, b);
  int *cofs = take(&ip, nb + 1), *cidx = take(&ip, nb), *tofs = take(&ip, nb + 1);
  int *tbody = take(&ip, nb), *tree = take(&ip, nb);
  P->body = take(&ip, nb), P->rcon = take(&ip, b), P->rrow = take(&ip, b);
  P->kspeed = take(&ip, nks);
  char dummy[8];
  int rc = rows(m, M, P, rofs, ridx, rdir, why ? why : dummy, why ? why_len : sizeof dummy);
  if (rc == AP_OK) {
    forest(M, P, parent, fofs, fidx, cofs, cidx, tofs, tbody, tree);
    ap_la_tree T = {(int)nb, M->k, M->b, parent, fofs, fidx, rofs, ridx, rdir, cofs, cidx,
                    P->T.ntree, tofs, tbody, tree, P->T.maxnf, 0, 0};
    P->T = T;
    for (int t = 0, p = 0; t < T.ntree; t++)   /* speeds of each tree, as the blocks list them */
      for (int a = tofs[t]; a < tofs[t + 1]; a++)
        for (int c = fofs[tbody[a]]; c < fofs[tbody[a] + 1]; c++) P->kspeed[p++] = fidx[c];
    rc = make_shadow(m, M, P);
  }
  if (rc == AP_OK) rc = ap_tree_hol_plan(P);
  if (rc != AP_OK) {
    ap_tree_plan_free(P);
    return rc;
  }
  capacities(M, P);
  if (P->nd == 0) {
    if (why && why_len) snprintf(why, why_len, "internal error: the tree workspace's layout");
    ap_tree_plan_free(P);
    return AP_ERR_INTERNAL;
  }
  *out = P;
  return AP_OK;
}

void ap_tree_plan_free(ap_tplan *P) {
  if (!P) return;
  free(P->sjoints);
  free(P->ints);
  free(P->hints);
  free(P);
}

void ap_tree_ws_init(const ap_tplan *P, double *dbl, int *ints, ap_tree_ws *ws) {
  ap_arena Ld, Li;
  ap_la_work_array la[2 * AP_LA_WORK_ARRAYS_MAX];
  memset(&ws->W, 0, sizeof ws->W);
  memset(&ws->CW, 0, sizeof ws->CW);
  int nla = ws_tables(P, ws, &Ld, &Li, la);
  memset(dbl, 0, sizeof(double) * P->nd);
  memset(ints, 0, sizeof(int) * P->ni);
  ws->P = P;
  int i = 0, j = 0;
#define WS_CARVE(f_, c_) f_ = dbl + Ld.e[i++].offset;
  TREE_WS_DOUBLES(WS_CARVE)
#undef WS_CARVE
#define WS_CARVE(f_, c_) f_ = ints + Li.e[j++].offset;
  TREE_WS_INTS(WS_CARVE)
#undef WS_CARVE
  for (int a = 0; a < nla; a++) {   /* lib/linalg's arrays, in the order ws_layout added them */
    if (la[a].dptr) *la[a].dptr = dbl + Ld.e[i++].offset;
    else *la[a].iptr = ints + Li.e[j++].offset;
  }
  ap_la_tree_work_setup(&P->T, P->lmax, &ws->W);
  if (P->comp) ap_la_comp_work_setup(&P->T, &ws->CW);
  ap_arena_fill_guards(&Ld, dbl);
  ap_arena_fill_guards(&Li, ints);
}

/* The first entries of the two blocks are ws->S and ws->avoid (TREE_WS_DOUBLES, _INTS). */
int ap_tree_ws_guard_msg(const ap_tree_ws *ws, const char *stage, char *msg, size_t len) {
  ap_arena Ld, Li;
  ap_la_work_array la[2 * AP_LA_WORK_ARRAYS_MAX];
  ws_tables(ws->P, NULL, &Ld, &Li, la);
  if (ap_arena_guard_msg(&Ld, ws->S, stage, msg, len) != 0) return -1;
  return ap_arena_guard_msg(&Li, ws->avoid, stage, msg, len);
}

/* ---- the compile-time choice ------------------------------------------------------------ */

static void plan_destroy(void *impl) { ap_tree_plan_free(impl); }

/* project_q and check_q of the body layer, on the shadow (its scratch is the data's). */
static int shadow_project_q(const ap_model *m, ap_data *d, double *q, double *S,
                            double *change) {
  return ap_bm_project_q(&ap_tree_plan(m)->sm, d, q, S, change);
}

static int shadow_check_q(const ap_model *m, ap_data *d, const double *q, double *S) {
  return ap_bm_check_q(&ap_tree_plan(m)->sm, d, q, S);
}

/* APPELL_PATH=tree|dense overrides the automatic choice (for running whole test suites on
 * one path: tree wherever the model allows it). The environment is read once per process, at
 * the first body model compiled (docs/large.md): a later setenv changes nothing, and no
 * compile reads the environment while another thread may be writing it. */
static int auto_min_k = AP_TREE_AUTO_K;
static pthread_once_t auto_once = PTHREAD_ONCE_INIT;

static void read_env_path(void) {
  const char *env = getenv("APPELL_PATH");
  if (env && strcmp(env, "tree") == 0) auto_min_k = 0;
  else if (env && strcmp(env, "dense") == 0) auto_min_k = INT_MAX;
}

int ap_tree_attach(ap_model *m, ap_path path, char *why, size_t why_len) {
  pthread_once(&auto_once, read_env_path);
  int min_k = auto_min_k;
  if (path == AP_PATH_DENSE || (path == AP_PATH_AUTO && m->k < min_k)) return AP_OK;
  char reason[256] = "";
  ap_tplan *P = NULL;
  int rc = ap_tree_plan_create(m, &P, reason, sizeof reason);
  if (rc == AP_ERR_UNSUPPORTED && path == AP_PATH_AUTO) return AP_OK;   /* the dense path */
  if (rc != AP_OK) {
    snprintf(why, why_len, "%s", rc == AP_ERR_NOMEM ? "out of memory planning the tree path"
             : reason);
    if (rc == AP_ERR_UNSUPPORTED)
      snprintf(why, why_len, "%s: the tree path cannot take it (path: dense)", reason);
    return rc;
  }
  ap_tree_ops(P, &P->ops);
  m->ops = &P->ops, m->ops_impl = P, m->ops_destroy = plan_destroy;
  if (m->ev.project_q) m->ev.project_q = shadow_project_q;
  if (m->ev.check_q) m->ev.check_q = shadow_check_q;
  /* wheel contacts: no phi hook (its Jacobian is dense, nphi x n), so CVODE BDF does not
   * project inside its step; project_q closes the rows after each step, as for Adams */
  if (ap_bm(m)->nloop) m->ev.phi = NULL;
  return AP_OK;
}
