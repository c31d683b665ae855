/* The differential tester's random models (docs/testing.md): a model is a list of bodies (each
 * with its joint and initial state), constraints and effects, kept as scene YAML fragments so
 * that the shrinker can drop elements and write the rest as a scene again. */
#ifndef AP_DIFFTEST_GEN_H
#define AP_DIFFTEST_GEN_H

#include <stddef.h>
#include <stdint.h>

#define DT_MAXB 8     /* bodies */
#define DT_MAXC 12    /* constraints */
#define DT_MAXE 8     /* effects */
#define DT_TXT 320    /* one YAML flow mapping */

enum { DT_FIXED, DT_REVOLUTE, DT_PRISMATIC, DT_PLANAR, DT_BALL, DT_FREE, DT_PLANE, DT_NKIND };
enum { DT_SH_NONE, DT_SH_SPHERE, DT_SH_ELLIPSOID, DT_SH_DISK, DT_SH_TORUS };

typedef struct dt_body {
  int live;
  int kind;                /* DT_FIXED ... DT_PLANE */
  int parent;              /* body index, -1 for the ground */
  int shape;               /* DT_SH_* */
  int driven;              /* its joint coordinate is driven */
  char body[DT_TXT];       /* bodies: entry, "{mass: ...}" */
  char joint[DT_TXT];      /* joints: entry */
  char init[DT_TXT];       /* initial: entry, "" for none */
} dt_body;

typedef struct dt_item {   /* a constraint or an effect */
  int live;
  int refs[2];             /* bodies (or joints) it names, -1 unused */
  char text[DT_TXT];
} dt_item;

typedef struct dt_model {
  uint64_t seed;
  int nb, nc, ne;
  dt_body b[DT_MAXB];
  dt_item c[DT_MAXC], e[DT_MAXE];
  char ground[96];         /* top-level ground: entry, "" for a fixed ground */
  double t_end;            /* s */
  int expect_tree;         /* every constraint acts on one body: the tree path applies */
} dt_model;

/* A random valid model from seed (loop closures are placed with the library's kinematics, so
 * this loads scenes through the public API). */
void dt_generate(uint64_t seed, dt_model *m);
/* 1: dt_generate gives some rolling contacts contact modes (gen_contact.c; difftest
 * --contacts); default 0 */
extern int dt_gen_contacts;
/* The scene YAML of m into buf (NUL-terminated); header (may be NULL) becomes a comment on top. */
void dt_write(const dt_model *m, const char *header, char *buf, size_t len);
/* Drop body i with its subtree and every constraint and effect naming a dropped body. */
void dt_drop_body(dt_model *m, int i);
int dt_live_bodies(const dt_model *m);

#endif
