/* Appell body layer (internal): the builder's storage, shared by builder.c, compile.c and
 * compile_con.c. */
#ifndef AP_MODEL_BUILDER_H
#define AP_MODEL_BUILDER_H

#include "model/model.h"

#define AP_NAME_MAX 64

typedef struct ap_bbody { ap_body_def def; char name[AP_NAME_MAX]; } ap_bbody;
typedef struct ap_bjoint { ap_joint_def def; char name[AP_NAME_MAX]; } ap_bjoint;
typedef struct ap_bcon { ap_constraint_def def; char name[AP_NAME_MAX]; } ap_bcon;
typedef struct ap_beff { ap_effect_def def; char name[AP_NAME_MAX]; } ap_beff;

struct ap_builder {
  char name[64];
  ap_bbody *bodies;
  ap_bjoint *joints;
  ap_bcon *cons;
  ap_beff *effs;
  int nb, cb, nj, cj, nc, cc, ne, ce;   /* counts and capacities */
  char msg[512];                        /* last error */
  ap_path path;                         /* ap_builder_set_path; AP_PATH_AUTO */
};

/* printf into b->msg; returns AP_ERR_ARG. */
int ap_builder_fail(ap_builder *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* compile_con.c: validate the constraints and lay out their rows in M (after the joints and
 * the coordinates); the suffix of row r of a constraint ("", ".x", ".z", ...; buf: 16 chars). */
int ap_compile_constraints(ap_builder *b, ap_bmodel *M);
const char *ap_con_row_suffix(const ap_mcon *c, int r, char *buf);

#endif
