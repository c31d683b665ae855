/* test_scene_input: hostile and mistaken scene input, in process (lib/scene).
 *
 * The loader's limits (nodes, bytes with aliases expanded, depth), with generated inputs: an
 * alias bomb, a long key above a wide alias tree, deep nesting, recursive and unknown aliases.
 * Duplicate keys are found in linear time: a 100 000-key mapping loads with fewer than 4 string
 * comparisons per key (a pairwise check would make 5e9; sc_tree_load_counted reports the
 * count, so the test does not depend on the machine's speed). The --set rules (elements are
 * not created, settings are, flow values, a sequence replaced by a scalar), YAML's .nan and
 * .inf, a directory given as the scene, and messages that do not repeat the key. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <appell/appell.h>

#include "check.h"
#include "scene/scene_int.h"

/* ---- helpers ------------------------------------------------------------------------------ */

/* The bombs below would take gigabytes from a loader without limits: this process may use
 * 1 GiB of address space (under AddressSanitizer, which reserves terabytes of it, 1 GiB of
 * resident memory), so that such a regression fails here instead of taking the machine. */
#if defined(__SANITIZE_ADDRESS__)
const char *__asan_default_options(void);
const char *__asan_default_options(void) { return "hard_rss_limit_mb=1024"; }
static void limit_memory(void) {}
#else
static void limit_memory(void) {
  struct rlimit r = {1UL << 30, 1UL << 30};
  AP_CHECK_EQ_INT(setrlimit(RLIMIT_AS, &r), 0);
}
#endif

/* A growable string. */
typedef struct text {
  char *s;
  size_t len, cap;
} text;

static void add(text *t, const char *s) {
  size_t n = strlen(s);
  if (t->len + n + 1 > t->cap) {
    t->cap = 2 * (t->len + n + 1);
    t->s = realloc(t->s, t->cap);
    if (!t->s) abort();
  }
  memcpy(t->s + t->len, s, n + 1);
  t->len += n;
}

/* Load text as a scene; the status, the message in msg. */
static int load(const char *scene, const char *const *sets, int nsets, char *msg, size_t len) {
  ap_scene *sc = NULL;
  msg[0] = '\0';
  int rc = ap_scene_load_string(scene, strlen(scene), "t.yaml", sets, nsets, &sc, msg, len);
  ap_scene_free(sc);
  return rc;
}

/* The tree of text (NULL on failure, with the message in msg). */
static sc_node *tree(const char *t, size_t len, long *compares, char *msg, size_t mlen) {
  sc_ctx c = {"t.yaml", "", AP_OK};
  sc_node *root = sc_tree_load_counted(&c, t, len, compares);
  snprintf(msg, mlen, "%s", c.msg);
  return root;
}

static void expect_msg(const char *msg, const char *what) {
  AP_CHECK(strstr(msg, what) != NULL);
  if (!strstr(msg, what)) fprintf(stderr, "  expected '%s'\n  got: %s\n", what, msg);
}

/* ---- the loader's limits ------------------------------------------------------------------ */

/* key: [&a [x * 10], &b [*a * 10], ..., then more aliases of the widest]: 10^levels nodes. */
static void alias_tree(text *t, int levels, int extra) {
  add(t, "[&a0 [x, x, x, x, x, x, x, x, x, x]");
  char buf[64];
  for (int l = 1; l < levels; l++) {
    snprintf(buf, sizeof buf, ", &a%d [", l);
    add(t, buf);
    for (int i = 0; i < 10; i++) {
      snprintf(buf, sizeof buf, "%s*a%d", i ? ", " : "", l - 1);
      add(t, buf);
    }
    add(t, "]");
  }
  for (int i = 0; i < extra; i++) {
    snprintf(buf, sizeof buf, ", *a%d", levels - 1);
    add(t, buf);
  }
  add(t, "]\n");
}

static void test_limits(void) {
  char msg[1024];
  long compares = 0;
  /* A long explicit key above an alias tree of 10^5 nodes: every node carries the key in its
   * path. Refused by the byte limit while reading, at the key's value. */
  text t = {0};
  add(&t, "? ");
  for (int i = 0; i < 20000; i++) add(&t, "k");
  add(&t, "\n: ");
  alias_tree(&t, 5, 5);
  AP_CHECK(tree(t.s, t.len, &compares, msg, sizeof msg) == NULL);
  expect_msg(msg, "t.yaml:2:");
  expect_msg(msg, "grows past 64 MiB");
  free(t.s);
  /* The classic bomb: 10^9 nodes from a few lines. */
  t = (text){0};
  add(&t, "bomb: ");
  alias_tree(&t, 9, 3);
  AP_CHECK(tree(t.s, t.len, &compares, msg, sizeof msg) == NULL);
  expect_msg(msg, "t.yaml:1:");
  AP_CHECK(strstr(msg, "grows past 64 MiB") || strstr(msg, "more than 1000000 nodes"));
  free(t.s);
  /* Nesting deeper than SC_MAX_DEPTH. */
  t = (text){0};
  for (int i = 0; i < 100; i++) add(&t, "[");
  for (int i = 0; i < 100; i++) add(&t, "]");
  AP_CHECK(tree(t.s, t.len, &compares, msg, sizeof msg) == NULL);
  expect_msg(msg, "nested more than 64 levels deep");
  free(t.s);
  const char *rec = "a: &a {b: [1, *a]}\n", *unknown = "a: [1, *nowhere]\n";
  AP_CHECK(tree(rec, strlen(rec), &compares, msg, sizeof msg) == NULL);
  expect_msg(msg, "t.yaml:1:15: a.b[1]: the alias '*a' is inside the node it refers to");
  AP_CHECK(tree(unknown, strlen(unknown), &compares, msg, sizeof msg) == NULL);
  expect_msg(msg, "t.yaml:1:8: a[1]: unknown alias '*nowhere'");
  /* Aliases that stay within the limits are copied, positions and all. */
  const char *ok = "a: &v {x: 1, y: [2, 3]}\nb: *v\n";
  sc_node *root = tree(ok, strlen(ok), &compares, msg, sizeof msg);
  AP_CHECK(root != NULL);
  const sc_node *b = sc_map_get(root, "b"), *y = sc_map_get(b, "y");
  AP_CHECK(y && y->kind == SC_SEQ && y->n == 2 && strcmp(y->kids[1]->path, "b.y[1]") == 0);
  AP_CHECK(y && y->line == 1);
  sc_tree_free(root);
}

/* 100 000 keys: linear work, and a duplicate found with the line of the first. */
static void test_many_keys(void) {
  enum { N = 100000 };
  text t = {0};
  char buf[64], msg[1024];
  add(&t, "bodies:\n");
  for (int i = 0; i < N; i++) {
    snprintf(buf, sizeof buf, "  b%d: {mass: 1}\n", i);
    add(&t, buf);
  }
  long compares = 0;
  sc_node *root = tree(t.s, t.len, &compares, msg, sizeof msg);
  AP_CHECK(root != NULL);
  if (!root) fprintf(stderr, "  %s\n", msg);
  const sc_node *bodies = sc_map_get(root, "bodies");
  AP_CHECK(bodies && bodies->n == N);
  AP_CHECK_LE((double)compares, 4.0 * N);   /* a pairwise check: N^2 / 2 = 5e9 */
  printf("100000 keys: %ld string comparisons\n", compares);
  sc_tree_free(root);
  add(&t, "  b5: {mass: 2}\n");
  AP_CHECK(tree(t.s, t.len, &compares, msg, sizeof msg) == NULL);
  char where[128];
  snprintf(where, sizeof where, "t.yaml:%d:3: bodies.b5: duplicate key 'b5' (first at line 7)",
           N + 2);
  expect_msg(msg, where);
  free(t.s);
}

/* ---- --set -------------------------------------------------------------------------------- */

static const char wheel[] =
    "bodies:\n"
    "  disk: {mass: 2, shape: {kind: disk, radius: 0.5}, inertia: [0.2, 0.2, 0.3]}\n"
    "joints:\n  disk: {kind: plane_contact}\n"
    "constraints:\n  roll: {kind: rolling, body: disk}\n"
    "effects:\n  gravity: {kind: gravity}\n";

/* Energy at the initial state of a scene rolling the disk, with one more override (NAN when
 * it does not load). The initial entries are created by --set: the scenes have none. */
static double energy(const char *scene, const char *extra) {
  const char *sets[] = {"initial.disk.tilt=70*deg", "initial.disk.spin_rate=5", extra};
  char msg[1024];
  ap_scene *sc = NULL;
  if (ap_scene_load_string(scene, strlen(scene), "t.yaml", sets, extra ? 3 : 2, &sc, msg,
                           sizeof msg)) {
    fprintf(stderr, "  %s\n", msg);
    return NAN;
  }
  const ap_model *m = ap_scene_model(sc);
  double x[32] = {0}, E = NAN;
  int n = ap_model_n(m);
  if (ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg) == AP_OK)
    ap_scene_energy(sc, 0.0, x, x + n, &E);
  ap_scene_free(sc);
  return E;
}

static void test_set(void) {
  char msg[1024];
  struct {
    const char *set, *what;
  } bad[] = {
      {"bodies.nosuch.mass=2", "t.yaml: --set bodies.nosuch.mass=2: bodies has no body 'nosuch' "
                               "(there are disk); --set changes the bodies"},
      {"bodies.dsik.mass=2", "bodies has no body 'dsik' (did you mean 'disk'?)"},
      {"joints.dsik.kind=free", "joints has no joint 'dsik' (did you mean 'disk'?)"},
      {"constraints.rol.kind=rolling", "constraints has no constraint 'rol' (did you mean "
                                       "'roll'?)"},
      {"effects.gravty.g=[0,0,-1]", "effects has no effect 'gravty' (did you mean 'gravity'?)"},
      {"initial.dsik.tilt=1", "there is no joint 'dsik' (did you mean 'disk'?)"},
      {"bodies.disk.mas=2", "bodies.disk.mas: unknown key 'mas' (did you mean 'mass'?)"},
      {"bodies.disk.com=[0, 0", "--set bodies.disk.com=[0, 0: the value is not valid YAML"},
      {"bodies.disk.com=[0, 0]", "--set bodies.disk.com=[0, 0]: bodies.disk.com: expected a "
                                 "sequence of 3 numbers"},
      {"bodies.disk.inertia=round", "bodies.disk.inertia (set by --set bodies.disk.inertia=round)"
                                    ": expected 'uniform'"},
      {"output.channels.3=energy", "output.channels has no entry '3'; give a whole sequence"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    AP_CHECK_EQ_INT(load(wheel, &bad[i].set, 1, msg, sizeof msg), AP_ERR_ARG);
    expect_msg(msg, bad[i].what);
  }
  /* Settings that are not written may be created (the initial entries above, com, a whole
   * section); a sequence may become a scalar form. Each gives the energy of the scene written
   * that way in the file. */
  char with_com[sizeof wheel + 64], uniform[sizeof wheel + 64];
  snprintf(with_com, sizeof with_com, "%s", wheel);
  char *at = strstr(with_com, "inertia:");
  AP_CHECK(at != NULL);
  if (!at) return;   /* (also keeps gcc's -Warray-bounds of the sanitizer build quiet) */
  memmove(at + 16, at, strlen(at) + 1);
  memcpy(at, "com: [0,0,0.1], ", 16);
  double E = energy(wheel, NULL), E_com = energy(wheel, "bodies.disk.com=[0, 0, 0.1]");
  AP_CHECK_NEAR(E_com, energy(with_com, NULL), 1e-12);
  AP_CHECK(fabs(E_com - E) > 0.1);   /* the raised centre of mass: m g dz = 0.67 J */
  at = strstr(wheel, "[0.2, 0.2, 0.3]");
  snprintf(uniform, sizeof uniform, "%.*suniform%s", (int)(at - wheel), wheel, at + 15);
  double E_uni = energy(wheel, "bodies.disk.inertia=uniform");
  AP_CHECK_NEAR(E_uni, energy(uniform, NULL), 1e-12);
  AP_CHECK(fabs(E_uni - E) > 0.1);   /* m r^2 / 4 = 0.125 instead of 0.2 about a diameter */
  AP_CHECK_NEAR(energy(wheel, "simulation.rtol=1e-9"), E, 1e-12);
}

/* ---- values, files, messages ---------------------------------------------------------------- */

static void test_values(void) {
  char msg[1024], scene[sizeof wheel + 64];
  struct {
    const char *from, *to, *what;
  } cases[] = {
      {"mass: 2", "mass: .nan", "t.yaml:2:16: bodies.disk.mass: expected a finite number, got "
                                "'.nan' (YAML's not-a-number)"},
      {"mass: 2", "mass: -.Inf", "got '-.Inf' (YAML's infinity)"},
      {"mass: 2", "mass: 1e999", "got '1e999' (beyond the range of a double)"},
      {"radius: 0.5", "radius: .INF", "bodies.disk.shape.radius: expected a finite number, got "
                                      "'.INF' (YAML's infinity)"},
      {"{kind: gravity}", "{kind: gravity, g: [0, 0, .nan]}", "effects.gravity.g[2]: expected a "
                                                              "finite number"},
      {"mass: 2", "mass: -2", "bodies.disk.mass: must be positive (got -2)"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const char *p = strstr(wheel, cases[i].from);
    snprintf(scene, sizeof scene, "%.*s%s%s", (int)(p - wheel), wheel, cases[i].to,
             p + strlen(cases[i].from));
    AP_CHECK_EQ_INT(load(scene, NULL, 0, msg, sizeof msg), AP_ERR_ARG);
    expect_msg(msg, cases[i].what);
  }
  const char *drive = "bodies:\n  arm: {mass: 1, inertia: [1, 1, 1]}\n"
                      "joints:\n  arm: {kind: revolute, drive: {angle: .inf}}\n";
  AP_CHECK_EQ_INT(load(drive, NULL, 0, msg, sizeof msg), AP_ERR_ARG);
  expect_msg(msg, "t.yaml:4:40: joints.arm.drive.angle: expected a finite number, got '.inf'");
  /* The key is named once: by the path, not again by the message. */
  const char *point = "bodies:\n  p: {mass: 1, shape: {kind: point}, inertia: uniform}\n"
                      "joints:\n  p: {kind: free}\n";
  AP_CHECK_EQ_INT(load(point, NULL, 0, msg, sizeof msg), AP_ERR_ARG);
  expect_msg(msg, "bodies.p.inertia: a uniform inertia needs a solid shape");
  AP_CHECK(strstr(msg, "inertia: inertia") == NULL);
  /* A directory as the scene. */
  char dir[] = "/tmp/appell_input_XXXXXX";
  AP_CHECK(mkdtemp(dir) != NULL);
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(dir, NULL, 0, &sc, msg, sizeof msg), AP_ERR_ARG);
  expect_msg(msg, "is a directory, not a scene file");
  rmdir(dir);
}

int main(void) {
  limit_memory();
  test_limits();
  test_many_keys();
  test_set();
  test_values();
  return ap_check_finish("test_scene_input");
}
