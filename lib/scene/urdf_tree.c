/* URDF import: names and the tree of a robot read by urdf.c.
 *
 * Links are found by name through an index sorted by name (binary search), and duplicate
 * names are the equal neighbours of a sorted list, so a file of many links costs
 * O(n log n), not O(n^2). The tree check follows each link's parents until it meets a link
 * already known to reach the root, stamping the path: meeting its own stamp is a cycle. Every
 * link is stamped once: O(n). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/urdf_int.h"

typedef struct ur_named {
  const char *name;
  int index;
} ur_named;

static int by_name(const void *a, const void *b) {
  const ur_named *x = a, *y = b;
  int c = strcmp(x->name, y->name);
  return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* Sorted (name, index) of n names at base + i * stride; NULL when out of memory. */
static ur_named *sorted(const void *base, int n, size_t stride) {
  ur_named *v = malloc(((size_t)n + 1) * sizeof *v);
  if (!v) return NULL;
  for (int i = 0; i < n; i++) v[i].name = (const char *)base + (size_t)i * stride, v[i].index = i;
  qsort(v, (size_t)n, sizeof *v, by_name);
  return v;
}

/* The first pair of equal names (a earlier in the file than b); 0 when none. */
static int duplicate(const ur_named *v, int n, int *a, int *b) {
  for (int i = 1; i < n; i++)
    if (strcmp(v[i - 1].name, v[i].name) == 0) {
      *a = v[i - 1].index, *b = v[i].index;
      return 1;
    }
  return 0;
}

int ur_index_links(ur_ctx *c, ur_robot *r, xmlNode *const *lnodes) {
  const ur_link *l = r->links;
  ur_named *u = sorted(l[0].urdf_name, r->nlinks, sizeof *l);
  ur_named *s = sorted(l[0].name, r->nlinks, sizeof *l);
  r->by_name = malloc(((size_t)r->nlinks + 1) * sizeof *r->by_name);
  int a, b, rc = AP_OK;
  if (!u || !s || !r->by_name) {
    rc = c->status = AP_ERR_NOMEM;
  } else if (duplicate(u, r->nlinks, &a, &b) || duplicate(s, r->nlinks, &a, &b)) {
    rc = ur_err(c, lnodes[b], "a second link of this name (the first is at line %d)%s",
                l[a].line, strcmp(l[a].urdf_name, l[b].urdf_name) ? " once its characters "
                "other than letters, digits, '_' and '-' are '_'" : "");
  } else {
    for (int i = 0; i < r->nlinks; i++) r->by_name[i] = u[i].index;
  }
  free(u);
  free(s);
  return rc;
}

int ur_find_link(const ur_robot *r, const char *urdf_name) {
  int lo = 0, hi = r->nlinks - 1;
  while (lo <= hi) {
    int mid = lo + (hi - lo) / 2, i = r->by_name[mid];
    int c = strcmp(r->links[i].urdf_name, urdf_name);
    if (c == 0) return i;
    if (c < 0) lo = mid + 1;
    else hi = mid - 1;
  }
  return -1;
}

int ur_check_joint_names(ur_ctx *c, const ur_robot *r, xmlNode *const *jnodes) {
  if (r->njoints == 0) return AP_OK;
  ur_named *v = sorted(r->joints[0].name, r->njoints, sizeof *r->joints);
  if (!v) return c->status = AP_ERR_NOMEM;
  int a, b, rc = AP_OK;
  if (duplicate(v, r->njoints, &a, &b))
    rc = ur_err(c, jnodes[b], "a second joint of this name (the first is at line %d)",
                r->joints[a].line);
  free(v);
  return rc;
}

static int parent_of(const ur_robot *r, int link) {
  return r->joints[r->links[link].parent_joint].parent;
}

/* The cycle that link `at` lies on, reported at its joint first in the file:
 * "the joints form a cycle: a -> b -> a" (parent to child). */
static int report_cycle(ur_ctx *c, const ur_robot *r, int at, xmlNode *const *jnodes) {
  int first = r->links[at].parent_joint, k = at;
  do {
    int j = r->links[k].parent_joint;
    if (r->joints[j].line < r->joints[first].line) first = j;
    k = r->joints[j].parent;
  } while (k != at);
  int *seq = malloc(((size_t)r->nlinks + 1) * sizeof *seq), n = 0;
  if (!seq) return c->status = AP_ERR_NOMEM;
  k = r->joints[first].parent;   /* from the parent of `first` up through the parents */
  do {
    seq[n++] = k;
    k = parent_of(r, k);
  } while (k != r->joints[first].parent);
  char chain[400];
  size_t used = 0;
  for (int i = 0; i <= n; i++) {   /* seq[0], seq[n-1] .. seq[1], seq[0] */
    const char *name = r->links[seq[i == 0 || i == n ? 0 : n - i]].urdf_name;
    if (used + strlen(name) + 9 >= sizeof chain) {
      snprintf(chain + used, sizeof chain - used, " -> ...");
      break;
    }
    used += (size_t)snprintf(chain + used, sizeof chain - used, "%s%s", i ? " -> " : "", name);
  }
  free(seq);
  return ur_err(c, jnodes[first], "the joints form a cycle: %s; a URDF is a tree (close loops "
                "in the scene with constraints)", chain);
}

int ur_check_tree(ur_ctx *c, ur_robot *r, xmlNode *const *jnodes, xmlNode *const *lnodes) {
  int *stamp = calloc((size_t)r->nlinks + 1, sizeof *stamp);   /* 0 new, i+1 on path i, -1 ok */
  if (!stamp) return c->status = AP_ERR_NOMEM;
  r->root = -1;
  int rc = AP_OK;
  for (int i = 0; i < r->nlinks && rc == AP_OK; i++) {
    int at = i;
    while (stamp[at] == 0 && r->links[at].parent_joint >= 0) stamp[at] = i + 1, at = parent_of(r, at);
    if (stamp[at] == i + 1) {
      rc = report_cycle(c, r, at, jnodes);
    } else if (stamp[at] == 0 && r->root >= 0) {   /* a link without a parent joint */
      rc = ur_err(c, lnodes[at], "a second root: links '%s' and '%s' have no parent joint, "
                  "and a URDF is one tree", r->links[r->root].urdf_name, r->links[at].urdf_name);
    } else {
      if (stamp[at] == 0) r->root = at;
      for (int k = i; k != at; k = parent_of(r, k)) stamp[k] = -1;
      stamp[at] = -1;
    }
  }
  free(stamp);
  if (rc == AP_OK && r->root < 0) rc = ur_err(c, NULL, "the robot has no link");
  return rc;
}
