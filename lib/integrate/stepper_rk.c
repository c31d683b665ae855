/* Our own explicit Runge-Kutta backend: the Dormand-Prince 8(5,3) pair "DOP853" (Hairer,
 * Norsett & Wanner, Solving Ordinary Differential Equations I, 2nd ed., Springer 1993,
 * section II.10; the coefficients are the published ones of the method, typed in below and
 * checked by tests/test_steppers.c against the rooted-tree order conditions).
 *
 * One step from (t, y) with step h, stages k_i = f(t + c_i h, y + h sum_j a_ij k_j):
 *   stages 1 ... 12       y1 = y + h sum b_j k_j, order 8 (b_2 ... b_5 = 0);
 *   stage 13 = f(t + h, y1), evaluated only once the step is accepted: it is k_1 of the next
 *                         step (first same as last), so an accepted step costs 12 evaluations
 *                         and a rejected one 11;
 *   stages 14 ... 16      evaluated only when dense output inside the step is asked for.
 * Error estimate (the "5,3" of the name): with E5 = y1 - y1^(5) (order-5 embedding) and
 * E3 = y1 - y1^(3) (order 3), per component scaled by sk = atol + rtol max(|y|, |y1|),
 *   err = |h| ||E5/h||^2 / sqrt(n (||E5/h||^2 + 0.01 ||E3/h||^2))
 * (sums of squares), which behaves like a local error estimate of order 8 rather than 5;
 * accepted when err <= 1.
 * Step size: a PI controller, h_new = h * clamp(0.9 err^-alpha err_prev^beta, 1/3, 6) with
 * alpha = 1/8 - 0.2 beta, beta = 0.04 (Gustafsson's PI control as in HNW section IV.2), and
 * no growth right after a rejection; the first step follows HNW's starting-step algorithm
 * (II.4). Dense output: the continuous extension of order 7 over the last step,
 *   u(s) = r1 + s (r2 + (1-s) (r3 + s (r4 + (1-s) (r5 + s (r6 + (1-s) (r7 + s r8))))))
 * with r1 = y, r2 = y1 - y, r3 = h k1 - r2, r4 = r2 - h k13 - r3, r5..r8 = h sum d_ij k_j.
 *
 * Layout: s->mem points to an rk_mem (below): the 16 stage vectors k (16 x n, one block), y of
 * the step start and of the candidate, the FSAL derivative f(t, yacc), and the dense-output
 * coefficients of the last accepted step. No SUNDIALS object is used.
 * Invariants: (s->t, s->yacc) is the last accepted state and rk->f holds f there when
 * rk->have_f; a failed step leaves both untouched. Every successful ap_step_one ends with the
 * evaluation f(t_new, y_new) at exactly the state it returns (the FSAL stage), which lets the
 * simulation driver reuse that evaluation (sim_step.c). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "integrate/stepper.h"

#define RK_STAGES 16        /* 12 + the FSAL stage + 3 for dense output */
#define RK_RETRIES 10       /* recoverable rhs failures retried per step, h / 4 each */
#define RK_MAX_REJECTS 100  /* error-test failures allowed in one step */
#define RK_SAFETY 0.9
#define RK_FAC_MIN (1.0 / 3.0)
#define RK_FAC_MAX 6.0
#define RK_BETA 0.04
#define RK_ALPHA (0.125 - 0.2 * RK_BETA)

/* ---- the method ------------------------------------------------------------------------- */

/* Stage i (0-based; the book's stage i + 1): c_i and the nonzero a_ij. */
typedef struct rk_row {
  double c;
  int n;
  int j[9];
  double a[9];
} rk_row;

static const rk_row rows[RK_STAGES] = {
    {0.0, 0, {0}, {0}},
    {0.526001519587677318785587544488e-01, 1, {0}, {5.26001519587677318785587544488e-02}},
    {0.789002279381515978178381316732e-01, 2, {0, 1},
     {1.97250569845378994544595329183e-02, 5.91751709536136983633785987549e-02}},
    {0.118350341907227396726757197510e+00, 2, {0, 2},
     {2.95875854768068491816892993775e-02, 8.87627564304205475450678981324e-02}},
    {0.281649658092772603273242802490e+00, 3, {0, 2, 3},
     {2.41365134159266685502369798665e-01, -8.84549479328286085344864962717e-01,
      9.24834003261792003115737966543e-01}},
    {0.333333333333333333333333333333e+00, 3, {0, 3, 4},
     {3.70370370370370370370370370370e-02, 1.70828608729473871279604482173e-01,
      1.25467687566822425016691814123e-01}},
    {0.25e+00, 4, {0, 3, 4, 5},
     {3.71093750000000000000000000000e-02, 1.70252211019544039314978060272e-01,
      6.02165389804559606850219397283e-02, -1.75781250000000000000000000000e-02}},
    {0.307692307692307692307692307692e+00, 5, {0, 3, 4, 5, 6},
     {3.70920001185047927108779319836e-02, 1.70383925712239993810214054705e-01,
      1.07262030446373284651809199168e-01, -1.53194377486244017527936158236e-02,
      8.27378916381402288758473766002e-03}},
    {0.651282051282051282051282051282e+00, 6, {0, 3, 4, 5, 6, 7},
     {6.24110958716075717114429577812e-01, -3.36089262944694129406857109825e+00,
      -8.68219346841726006818189891453e-01, 2.75920996994467083049415600797e+01,
      2.01540675504778934086186788979e+01, -4.34898841810699588477366255144e+01}},
    {0.6e+00, 7, {0, 3, 4, 5, 6, 7, 8},
     {4.77662536438264365890433908527e-01, -2.48811461997166764192642586468e+00,
      -5.90290826836842996371446475743e-01, 2.12300514481811942347288949897e+01,
      1.52792336328824235832596922938e+01, -3.32882109689848629194453265587e+01,
      -2.03312017085086261358222928593e-02}},
    {0.857142857142857142857142857142e+00, 8, {0, 3, 4, 5, 6, 7, 8, 9},
     {-9.37142430085987325717040216580e-01, 5.18637242884406370830023853209e+00,
      1.09143734899672957818500254654e+00, -8.14978701074692612513997267357e+00,
      -1.85200656599969598641566180701e+01, 2.27394870993505042818970056734e+01,
      2.49360555267965238987089396762e+00, -3.04676447189821950038236690220e+00}},
    {1.0, 9, {0, 3, 4, 5, 6, 7, 8, 9, 10},
     {2.27331014751653820792359768449e+00, -1.05344954667372501984066689879e+01,
      -2.00087205822486249909675718444e+00, -1.79589318631187989172765950534e+01,
      2.79488845294199600508499808837e+01, -2.85899827713502369474065508674e+00,
      -8.87285693353062954433549289258e+00, 1.23605671757943030647266201528e+01,
      6.43392746015763530355970484046e-01}},
    {1.0, 0, {0}, {0}},   /* the FSAL stage: its row is b (y1 itself), see fsal_row() */
    {0.1e+00, 8, {0, 6, 7, 8, 9, 10, 11, 12},
     {5.61675022830479523392909219681e-02, 2.53500210216624811088794765333e-01,
      -2.46239037470802489917441475441e-01, -1.24191423263816360469010140626e-01,
      1.53291798278765697312063226850e-01, 8.20105229563468988491666602057e-03,
      7.56789766054569976138603589584e-03, -8.29800000000000000000000000000e-03}},
    {0.2e+00, 8, {0, 5, 6, 7, 10, 11, 12, 13},
     {3.18346481635021405060768473261e-02, 2.83009096723667755288322961402e-02,
      5.35419883074385676223797384372e-02, -5.49237485713909884646569340306e-02,
      -1.08347328697249322858509316994e-04, 3.82571090835658412954920192323e-04,
      -3.40465008687404560802977114492e-04, 1.41312443674632500278074618366e-01}},
    {0.777777777777777777777777777778e+00, 8, {0, 5, 6, 7, 8, 12, 13, 14},
     {-4.28896301583791923408573538692e-01, -4.69762141536116384314449447206e+00,
      7.68342119606259904184240953878e+00, 4.06898981839711007970213554331e+00,
      3.56727187455281109270669543021e-01, -1.39902416515901462129418009734e-03,
      2.94751478915277233895562721490e+00, -9.15095847217987001081870187138e+00}},
};

/* Weights of y1 (order 8) and of the error estimates, on stages 1, 6 ... 12 (0-based 0, 5..11). */
static const int bj[8] = {0, 5, 6, 7, 8, 9, 10, 11};
static const double bw[8] = {
    5.42937341165687622380535766363e-02, 4.45031289275240888144113950566e+00,
    1.89151789931450038304281599044e+00, -5.80120396001058478146721142270e+00,
    3.11164366957819894408916062370e-01, -1.52160949662516078556178806805e-01,
    2.01365400804030348374776537501e-01, 4.47106157277725905176885569043e-02};
/* E5 / h = sum er_j k_j: y1 minus the order-5 embedding. */
static const double er[8] = {
    0.13120044994194880732501029960e-01, -0.12251564463762044407205697530e+01,
    -0.49575894965725019152140799520e+00, 0.16643771824549865369615304150e+01,
    -0.35032884874997368168864872900e+00, 0.33417911871301747902973188410e+00,
    0.81923206485115712465707426130e-01, -0.22355307863886295258844278450e-01};
/* The order-3 embedding: weights on stages 1, 9, 12 (0-based 0, 8, 11). */
static const int b3j[3] = {0, 8, 11};
static const double b3w[3] = {0.244094488188976377952755905512e+00,
                              0.733846688281611857341361741547e+00,
                              0.220588235294117647058823529412e-01};

/* Dense output r5 ... r8 = h sum_j d[r][p] k_{dj[p]}, stages 1, 6 ... 16. */
static const int dj[12] = {0, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
static const double dw[4][12] = {
    {-0.84289382761090128651353491142e+01, 0.56671495351937776962531783590e+00,
     -0.30689499459498916912797304727e+01, 0.23846676565120698287728149680e+01,
     0.21170345824450282767155149946e+01, -0.87139158377797299206789907490e+00,
     0.22404374302607882758541771650e+01, 0.63157877876946881815570249290e+00,
     -0.88990336451333310820698117400e-01, 0.18148505520854727256656404962e+02,
     -0.91946323924783554000451984436e+01, -0.44360363875948939664310572000e+01},
    {0.10427508642579134603413151009e+02, 0.24228349177525818288430175319e+03,
     0.16520045171727028198505394887e+03, -0.37454675472269020279518312152e+03,
     -0.22113666853125306036270938578e+02, 0.77334326684722638389603898808e+01,
     -0.30674084731089398182061213626e+02, -0.93321305264302278729567221706e+01,
     0.15697238121770843886131091075e+02, -0.31139403219565177677282850411e+02,
     -0.93529243588444783865713862664e+01, 0.35816841486394083752465898540e+02},
    {0.19985053242002433820987653617e+02, -0.38703730874935176555105901742e+03,
     -0.18917813819516756882830838328e+03, 0.52780815920542364900561016686e+03,
     -0.11573902539959630126141871134e+02, 0.68812326946963000169666922661e+01,
     -0.10006050966910838403183860980e+01, 0.77771377980534432092869265740e+00,
     -0.27782057523535084065932004339e+01, -0.60196695231264120758267380846e+02,
     0.84320405506677161018159903784e+02, 0.11992291136182789328035130030e+02},
    {-0.25693933462703749003312586129e+02, -0.15418974869023643374053993627e+03,
     -0.23152937917604549567536039109e+03, 0.35763911791061412378285349910e+03,
     0.93405324183624310003907691704e+02, -0.37458323136451633156875139351e+02,
     0.10409964950896230045147246184e+03, 0.29840293426660503123344363579e+02,
     -0.43533456590011143754432175058e+02, 0.96324553959188282948394950600e+02,
     -0.39177261675615439165231486172e+02, -0.14972683625798562581422125276e+03}};

/* ---- the tables for tests ----------------------------------------------------------------- */

/* A (ns x ns, row-major) and c of the first ns stages (ns <= RK_STAGES); row 13 is b. */
static void full_table(int ns, double *A, double *c) {
  memset(A, 0, sizeof(double) * (size_t)(ns * ns));
  for (int i = 0; i < ns; i++) {
    c[i] = rows[i].c;
    for (int p = 0; p < rows[i].n; p++) A[i * ns + rows[i].j[p]] = rows[i].a[p];
  }
  if (ns > 12)
    for (int p = 0; p < 8; p++) A[12 * ns + bj[p]] = bw[p];
}

int ap_step_rk_butcher(const ap_step_method *meth, int max_s, int *s, int *q, double *A,
                       double *b, double *c, double *d) {
  (void)meth;
  *s = 13, *q = 8;
  if (max_s < 13) return AP_ERR_ARG;
  full_table(13, A, c);
  memset(b, 0, sizeof(double) * 13);
  memset(d, 0, sizeof(double) * 13);
  for (int p = 0; p < 8; p++) b[bj[p]] = bw[p], d[bj[p]] = bw[p] - er[p];
  return AP_OK;
}

int ap_step_rk_tables(int max_s, int *s, double *A, double *c, double *b3, double theta,
                      double *w) {
  *s = RK_STAGES;
  if (max_s < RK_STAGES) return AP_ERR_ARG;
  full_table(RK_STAGES, A, c);
  memset(b3, 0, sizeof(double) * RK_STAGES);
  for (int p = 0; p < 3; p++) b3[b3j[p]] = b3w[p];
  /* u(theta) = y + h sum_j w_j k_j: the interpolant above with r2 = h sum b_j k_j */
  double b[RK_STAGES] = {0}, ds[4][RK_STAGES] = {{0}}, s1 = 1.0 - theta;
  for (int p = 0; p < 8; p++) b[bj[p]] = bw[p];
  for (int r = 0; r < 4; r++)
    for (int p = 0; p < 12; p++) ds[r][dj[p]] = dw[r][p];
  for (int j = 0; j < RK_STAGES; j++) {
    double e1 = j == 0, e13 = j == 12;
    double tail = ds[0][j] + theta * (ds[1][j] + s1 * (ds[2][j] + theta * ds[3][j]));
    w[j] = theta * (b[j] + s1 * ((e1 - b[j]) + theta * ((2 * b[j] - e1 - e13) + s1 * tail)));
  }
  return AP_OK;
}

/* ---- state ----------------------------------------------------------------------------- */

typedef struct rk_mem {
  double *k[RK_STAGES];  /* stage derivatives, n each (one block); k[12] = f(t1, y1) */
  double *y0;            /* (n) start of the last step (dense output) */
  double *y1;            /* (n) candidate / end of the last accepted step */
  double *ys;            /* (n) stage argument */
  double *cont;          /* (8 x n) r1 ... r8 of the last step */
  double *f;             /* (n) f(s->t, yacc) when have_f */
  int have_f;
  int dense;             /* 0 none, 1 last step known (r1..r4), 2 r5..r8 too */
  double h;              /* next step to try; 0 = choose the first step */
  double err_prev;       /* error of the last accepted step (PI control) */
  int rejected;          /* the last attempt was rejected: no growth on the next success */
  double t0, h_last;     /* the last accepted step [t0, t0 + h_last] */
  long steps, rejects;
} rk_mem;

static rk_mem *mem_of(const ap_stepper *s) { return (rk_mem *)s->mem; }

static void rk_destroy(ap_stepper *s) {
  rk_mem *rk = mem_of(s);
  if (rk) free(rk->k[0]);
  free(rk);
  s->mem = NULL;
  ap_step_release(s);
}

static int rk_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                     const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                     size_t msg_len) {
  ap_stepper *s = NULL;
  int rc = ap_step_alloc(meth, n, f, user, t0, y0, o, &s, msg, msg_len);
  if (rc != AP_OK) return rc;
  rk_mem *rk = calloc(1, sizeof *rk);
  double *block = rk ? calloc((size_t)n * (RK_STAGES + 4 + 8), sizeof(double)) : NULL;
  s->mem = rk;
  if (!block) {
    rk_destroy(s);
    if (msg && msg_len) snprintf(msg, msg_len, "%s: out of memory", meth->name);
    return AP_ERR_NOMEM;
  }
  for (int i = 0; i < RK_STAGES; i++) rk->k[i] = block + (size_t)i * n;
  rk->y0 = block + (size_t)RK_STAGES * n;
  rk->y1 = rk->y0 + n, rk->ys = rk->y1 + n, rk->f = rk->ys + n, rk->cont = rk->f + n;
  rk->h = s->o.h_fixed > 0 ? s->o.h_fixed : s->o.h_init;
  rk->err_prev = 1e-4;
  *out = s;
  return AP_OK;
}

/* Restart at (t, y): the FSAL derivative is gone, the step size and controller stay. */
static int rk_reset(ap_stepper *s, double t, const double *y) {
  rk_mem *rk = mem_of(s);
  rk->have_f = 0, rk->dense = 0;
  if (s->o.h_fixed > 0) rk->h = s->o.h_fixed;
  ap_step_accept(s, t, y);
  return AP_OK;
}

/* The same trajectory in other coordinates: as reset, and f(t, y) known when ydot != NULL. */
int ap_step_rk_restart(ap_stepper *s, double t, const double *y, const double *ydot) {
  rk_reset(s, t, y);
  rk_mem *rk = mem_of(s);
  if (ydot) memcpy(rk->f, ydot, sizeof(double) * (size_t)s->n), rk->have_f = 1;
  return AP_OK;
}

/* ---- one step ---------------------------------------------------------------------------- */

/* ys = y + h sum_j a_ij k_j (row i). */
static void stage_arg(const rk_mem *rk, int i, int n, double h, const double *y) {
  const rk_row *r = &rows[i];
  for (int x = 0; x < n; x++) {
    double acc = 0.0;
    for (int p = 0; p < r->n; p++) acc += r->a[p] * rk->k[r->j[p]][x];
    rk->ys[x] = y[x] + h * acc;
  }
}

/* y1 = y + h sum b_j k_j and the scaled error (see the note at the top); NaN if not finite. */
static double solution_and_error(ap_stepper *s, rk_mem *rk, double h, const double *y) {
  int n = s->n;
  double e5 = 0.0, e3 = 0.0;
  for (int x = 0; x < n; x++) {
    double s8 = 0.0, s5 = 0.0, s3 = 0.0;
    for (int p = 0; p < 8; p++) {
      double kx = rk->k[bj[p]][x];
      s8 += bw[p] * kx, s5 += er[p] * kx;
    }
    for (int p = 0; p < 3; p++) s3 += b3w[p] * rk->k[b3j[p]][x];
    rk->y1[x] = y[x] + h * s8;
    double sk = s->o.atol + s->o.rtol * fmax(fabs(y[x]), fabs(rk->y1[x]));
    if (s->o.weight) sk /= s->o.weight[x];   /* weight 0: sk = inf, the term vanishes */
    e5 += (s5 / sk) * (s5 / sk), e3 += ((s8 - s3) / sk) * ((s8 - s3) / sk);
  }
  double den = e5 + 0.01 * e3, wn = ap_step_weight_norm(s);
  double err = wn * fabs(h) * e5 / sqrt(n * (den > 0.0 ? den : 1.0));
  return isfinite(err) ? err : NAN;
}

/* Stages 2 ... 12 from k[0] = f(t, y); returns the rhs code (0 ok) and *err. */
static int attempt(ap_stepper *s, rk_mem *rk, double t, double h, const double *y, double *err) {
  for (int i = 1; i < 12; i++) {
    stage_arg(rk, i, s->n, h, y);
    int rc = ap_step_rhs_eval(s, t + rows[i].c * h, rk->ys, rk->k[i]);
    if (rc != 0) return rc;
  }
  *err = solution_and_error(s, rk, h, y);
  if (isnan(*err)) s->rhs_nan = 1;
  return isnan(*err) ? 1 : 0;
}

/* Weighted RMS norm with the tolerances at y. */
static double rms(const ap_stepper *s, const double *v, const double *y) {
  double sum = 0.0;
  for (int x = 0; x < s->n; x++) {
    double r = ap_step_weight(s, x) * v[x] / (s->o.atol + s->o.rtol * fabs(y[x]));
    sum += r * r;
  }
  return ap_step_weight_norm(s) * sqrt(sum / s->n);
}

/* The first step (HNW II.4): an Euler step of size h0 = 0.01 |y| / |f| estimates f', and
 * h = (0.01 / max(|f|, |f'|))^(1/8), at most 100 h0. One evaluation (k[1] as scratch). */
static double first_step(ap_stepper *s, rk_mem *rk, double t, const double *y) {
  double d0 = rms(s, y, y), d1 = rms(s, rk->k[0], y);
  double h0 = d0 < 1e-5 || d1 < 1e-5 ? 1e-6 : 0.01 * d0 / d1;
  if (s->o.h_max > 0) h0 = fmin(h0, s->o.h_max);
  for (int x = 0; x < s->n; x++) rk->ys[x] = y[x] + h0 * rk->k[0][x];
  if (ap_step_rhs_eval(s, t + h0, rk->ys, rk->k[1]) != 0) return h0;
  for (int x = 0; x < s->n; x++) rk->k[1][x] -= rk->k[0][x];
  double d2 = rms(s, rk->k[1], y) / h0, dm = fmax(d1, d2);
  double h1 = dm <= 1e-15 ? fmax(1e-6, 1e-3 * h0) : pow(0.01 / dm, 0.125);
  return fmin(100.0 * h0, h1);
}

/* The step after an accepted one with error err (PI control). */
static double next_h(rk_mem *rk, double h, double err) {
  double fac = RK_SAFETY * pow(fmax(err, 1e-12), -RK_ALPHA) * pow(rk->err_prev, RK_BETA);
  fac = fmin(fmax(fac, RK_FAC_MIN), rk->rejected ? 1.0 : RK_FAC_MAX);
  rk->err_prev = fmax(err, 1e-4);
  return h * fac;
}

static int step_fail(ap_stepper *s, int code, const char *what) {
  s->sun_msg[0] = '\0';
  return ap_step_fail(s, code, what);
}

/* Accept the step to (t1, y1) whose FSAL stage k[12] = f(t1, y1) is evaluated. */
static void accept(ap_stepper *s, rk_mem *rk, double t1, double h) {
  memcpy(rk->y0, s->yacc, sizeof(double) * (size_t)s->n);
  memcpy(rk->f, rk->k[12], sizeof(double) * (size_t)s->n);
  rk->t0 = s->t, rk->h_last = h, rk->dense = 1, rk->have_f = 1, rk->steps++;
  ap_step_accept(s, t1, rk->y1);
}

static int rk_one(ap_stepper *s, double tstop, double *tout, double *yout) {
  (void)tout, (void)yout;                        /* the dispatcher copies (s->t, yacc) out */
  rk_mem *rk = mem_of(s);
  const double t = s->t, *y = s->yacc;
  int fixed = s->o.h_fixed > 0, retries = 0, rejects = 0, rc = 0;
  if (!rk->have_f) {
    rc = ap_step_rhs_eval(s, t, y, rk->f);
    if (rc != 0) return step_fail(s, rc, "rhs at the step start");
    rk->have_f = 1;
  }
  memcpy(rk->k[0], rk->f, sizeof(double) * (size_t)s->n);
  if (!(rk->h > 0)) rk->h = first_step(s, rk, t, y);
  for (;;) {
    double h = rk->h, err = 0.0;
    if (s->o.h_max > 0 && h > s->o.h_max) h = s->o.h_max;
    /* land on tstop: stretch the step by up to 1 % rather than leave a sliver (fixed steps
     * only by round-off) */
    int clipped = t + (fixed ? 1.0 + 1e-10 : 1.01) * h >= tstop;
    if (clipped) h = tstop - t;
    double t1 = clipped ? tstop : t + h;
    if (!(h > 16.0 * DBL_EPSILON * fmax(fabs(t), 1e-300)) || t1 == t)
      return step_fail(s, 0, "step size too small");
    rc = attempt(s, rk, t, h, y, &err);
    if (rc == 0 && (fixed || err <= 1.0)) rc = ap_step_rhs_eval(s, t1, rk->y1, rk->k[12]);
    if (rc < 0) return step_fail(s, rc, "the right-hand side stopped the step");
    if (rc > 0) {                                /* recoverable: a quarter of the step */
      if (retries++ == RK_RETRIES) return step_fail(s, rc, "retries exhausted");
      rk->h = 0.25 * h, rk->rejected = 1;
      continue;
    }
    if (fixed || err <= 1.0) {
      accept(s, rk, t1, h);
      double hn = fixed ? s->o.h_fixed : next_h(rk, h, err);
      /* a step shortened to land on tstop says little about the next one */
      rk->h = fixed || !clipped ? hn : fmax(hn, rk->h);
      rk->rejected = 0;
      return AP_OK;
    }
    rk->rejects++;
    if (++rejects == RK_MAX_REJECTS) return step_fail(s, 0, "too many error-test failures");
    rk->h = h * fmax(RK_FAC_MIN, RK_SAFETY * pow(err, -0.125)), rk->rejected = 1;
  }
}

/* ---- dense output ------------------------------------------------------------------------ */

/* r1 ... r8 of the last step; stages 14 ... 16 are evaluated the first time. */
static int prepare_dense(ap_stepper *s, rk_mem *rk) {
  int n = s->n;
  double h = rk->h_last, *r = rk->cont;
  if (rk->dense == 2) return 0;
  for (int i = 13; i < RK_STAGES; i++) {
    stage_arg(rk, i, n, h, rk->y0);
    int rc = ap_step_rhs_eval(s, rk->t0 + rows[i].c * h, rk->ys, rk->k[i]);
    if (rc != 0) return rc;
  }
  for (int x = 0; x < n; x++) {
    double d = s->yacc[x] - rk->y0[x], b = h * rk->k[0][x] - d;
    r[x] = rk->y0[x], r[n + x] = d, r[2 * n + x] = b, r[3 * n + x] = d - h * rk->k[12][x] - b;
    for (int q = 0; q < 4; q++) {
      double acc = 0.0;
      for (int p = 0; p < 12; p++) acc += dw[q][p] * rk->k[dj[p]][x];
      r[(4 + q) * n + x] = h * acc;
    }
  }
  rk->dense = 2;
  return 0;
}

static int rk_dky(ap_stepper *s, double t, double *y) {
  rk_mem *rk = mem_of(s);
  int n = s->n;
  if (t == s->t) {
    memcpy(y, s->yacc, sizeof(double) * (size_t)n);
    return AP_OK;
  }
  if (!rk->dense || t < rk->t0 || t > s->t) {
    snprintf(s->msg, sizeof s->msg, "%s: no dense output at t = %.17g (the last step covers "
             "[%.17g, %.17g])", s->meth->name, t, rk->dense ? rk->t0 : s->t, s->t);
    return AP_ERR_ARG;
  }
  s->rhs_neg = s->rhs_pos = s->rhs_nan = 0;
  int rc = prepare_dense(s, rk);
  if (rc != 0) {
    snprintf(s->msg, sizeof s->msg, "%s: dense output at t = %.17g: the right-hand side "
             "failed (%d)", s->meth->name, t, rc);
    return rc < 0 ? AP_ERR_CALLBACK : s->rhs_nan ? AP_ERR_NAN : AP_ERR_SOLVER;
  }
  double th = (t - rk->t0) / rk->h_last, t1 = 1.0 - th;
  const double *r = rk->cont;
  for (int x = 0; x < n; x++) {
    double u = r[4 * n + x] + th * (r[5 * n + x] + t1 * (r[6 * n + x] + th * r[7 * n + x]));
    y[x] = r[x] + th * (r[n + x] + t1 * (r[2 * n + x] + th * (r[3 * n + x] + t1 * u)));
  }
  return AP_OK;
}

static void rk_stats(const ap_stepper *s, ap_step_stats *st) {
  const rk_mem *rk = mem_of(s);
  st->steps = rk->steps, st->err_fails = rk->rejects, st->h_last = rk->h_last;
}

const ap_step_backend ap_step_rk = {"Appell explicit RK", rk_create, rk_reset, rk_one,
                                    rk_dky, rk_stats, rk_destroy};
