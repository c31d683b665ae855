/* The root finder shared by the events (event.c) and the loop-rank monitor (sim_rank.c):
 * Illinois-modified regula falsi on a bracket of a function of time (root.c). */
#ifndef AP_INTEGRATE_ROOT_H
#define AP_INTEGRATE_ROOT_H

/* The function: its value at t into *g; a status other than AP_OK ends the search with it. */
typedef int (*ap_drv_root_fn)(void *ctx, double t, double *g);

/* Which side a value of exactly 0 belongs to. */
typedef enum {
  AP_ROOT_ZERO_ENTERED = 0,   /* the side entered: 0 is never on the old side (events) */
  AP_ROOT_ZERO_NEGATIVE = -1  /* the side of the negative values (the sign of a determinant) */
} ap_drv_root_zero;

/* The crossing in [ta, tb] of fn, which is on the side `old` (+1 or -1) at ta with the value ga
 * and has left it at tb with gb: Illinois regula falsi, bisecting whenever a step of the
 * iteration fails to halve the bracket, until gb is 0, the bracket is 4 ulps of t wide, or
 * after `iter` evaluations. *troot: the bracket's right end, on the side entered (the event
 * never fires twice at one crossing). AP_OK or fn's failure. */
int ap_drv_root_locate(ap_drv_root_fn fn, void *ctx, int old, ap_drv_root_zero zero, int iter,
                       double ta, double ga, double tb, double gb, double *troot);

#endif
