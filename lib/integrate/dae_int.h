/* The DAE driver's internals (dae.c: creation, stepping, the kept rows; dae_res.c: the
 * residual, IDA's error weights and the Newton matrix). The method is described at the top of
 * dae.c. */
#ifndef AP_INTEGRATE_DAE_INT_H
#define AP_INTEGRATE_DAE_INT_H

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "core/core.h"
#include "integrate/dae.h"

#define AP_DAE_POOL 48   /* vectors of the pool (nvpool.c): every clone IDA makes */

/* atol's floor for IDA, in ulps of the typical |q| or |v| (see "Tolerances" above). */
#define AP_DAE_ATOL_EPS 10.0

struct ap_dae {
  const ap_model *m;
  ap_data *d;
  SUNContext ctx;
  void *mem;
  N_Vector yy, yp, id;      /* from pool, with every vector IDA clones (nvpool.c) */
  struct ap_nvpool *pool;
  N_Vector dk;              /* dense output for events (ap_dae_dky), made at the first use */
  N_Vector rr;              /* the residual at a (re)start (initial_multipliers), made at
                               creation: a restart mid-run allocates nothing */
  SUNMatrix J;
  SUNLinearSolver LS;
  int n, k, b, bs, nphi, nps, ny;  /* ny = n + k + bs + nps */
  int *rows, *prows;        /* (bs), (nps) the kept rows of A and of phi, ascending */
  double rtol, atol;
  double qtyp, vtyp;        /* typical |q|, |v|: difference-quotient increments */
  double *Phi_q, *phi;      /* (nphi x n) Jacobian of phi in q, (nphi) phi: all rows */
  double *jg, *jN, *jA, *jP;/* the Jacobian's base point: g, N, A_s (bs x k), Phi_s (nps x n) */
  double *Ms, *gf;          /* M = g^-1 A_s^T (k x bs); g's factor */
  double *Pl, *Pm;          /* the multipliers' maps for their weights: (bs x k), (nps x n) */
  double *Sf, *colw;        /* their factor (max(b, nphi)^2) and a column (max(b, nphi)) */
  ap_dae_couple cp;         /* coupled forces of the multipliers (fn NULL: none) */
  double *W, *jW;           /* (k x b) their columns, at the residual and at the Jacobian's
                               base point */
  double *lamf, *lF, *lw;   /* cp.load: lambda on all rows (b), its force (k), work (b + 2 k) */
  double *lFv, *lFl;        /* cp.lin: its derivatives in v' (k x k) and lambda (k x b) */
  double *qr, *qr_sub;      /* row_qr's scratch; the kept rows as a matrix */
  int *jpvt, *cand;         /* row_qr's row order and integer scratch; a candidate choice */
  long nres;                /* residual evaluations, the Newton matrix's included */
  long base_steps, base_netf, base_ncf;   /* IDA's counters before its last restart */
  int res_status;           /* last failure of the residual */
  int nomem;                /* SUNDIALS reported a failed allocation */
  char res_msg[512];
  char msg[1024];
};

/* dae_res.c. IDA's callbacks (user = the ap_dae): the residual F(t, y, y') (records a
 * failure's status and message in res_status, res_msg), the error weights, the Newton matrix
 * dF/dy + cj dF/dy', and the error handler (keeps IDA's message, notes a failed allocation). */
int ap_dae_residual(double t, N_Vector yy, N_Vector yp, N_Vector rr, void *user);
int ap_dae_weights(N_Vector yv, N_Vector ewt, void *user);
int ap_dae_jacobian(double t, double cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                    void *user, N_Vector t1, N_Vector t2, N_Vector t3);
void ap_dae_err_handler(int code, const char *module, const char *function, char *text,
                        void *user);
/* The loads' coupled force (ap_dae_couple.lin) at the data's state into lFv, lFl, its
 * lambda part added to jA (bs x k, the kept rows' A_s + W_s^T; NULL: not); AP_OK without
 * cp.load, else AP_OK or a status with res_msg set. */
int ap_dae_load_lin(ap_dae *s, double *jA);
/* The multipliers' maps Pl, Pm for their weights, from the data after a residual evaluation. */
void ap_dae_multiplier_scales(ap_dae *s);

#endif
