/* appell linearize: operating points, linearization, eigenvalues and speed sweeps of a Model
 * (include/appell/analyze.h, docs/linearize.md), as `appell linearize` computes them.
 *
 * _appell.linearize(model, speed, about, free, inputs, states, keep_cyclic, sweep, ptol) loads
 * the model's scene again from its text and overrides (ap_scene_lin_guess_load: the guess of
 * the operating point and the speed direction of its linearize: section), makes a linearizer
 * with the section's settings and the keyword overrides, and returns a dict of NumPy arrays:
 *  - one point (sweep None): speed, t, q, v (the operating point), state_names, cyclic, A,
 *    A_error, B, input_names, rates, subsystem (state names), A_sub, eigenvalues (complex),
 *    rcond, rcondv, error, eigenvectors (complex, column j for eigenvalue j);
 *  - a speed sweep (sweep = the speeds, ascending): p, subsystem, eigenvalues (count x n,
 *    complex, column j follows one eigenvalue by continuity) and points (characteristic
 *    speeds: kind 'crossing' or 'meeting', p, p_err, value, index, rising).
 * Matrices are copied from the library's column-major storage into ordinary arrays. The work
 * runs with the GIL released; the linearizer is local to the call. */
#include "_ext.h"

#include <math.h>
#include <time.h>
#include <string.h>

typedef struct lin_args {
  double speed;            /* NaN: the scene's own */
  int about;               /* -1: the section's */
  const char **free, **inputs, **states;   /* NULL: the section's */
  int keep_cyclic;
  double *sweep;
  Py_ssize_t count;
  double ptol;
} lin_args;

typedef struct lin_run {
  ap_scene_lin_guess g;
  ap_lin *L;
  int sel[64], ns;
  ap_lin_sweep sw;
  int swept;
  char msg[1024];
} lin_run;

/* ---- the computation (no Python objects: runs without the GIL) --------------------------- */

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int select_states(lin_run *r, const char *const *names) {
  r->ns = 0;
  for (int i = 0; names && names[i]; i++) {
    int s = ap_lin_find_state(r->L, names[i]);
    if (s < 0 || r->ns >= 64) {
      int len = snprintf(r->msg, sizeof r->msg, "no state named '%s'; the states are:", names[i]);
      for (int j = 0; j < ap_lin_nx(r->L) && len > 0 && (size_t)len < sizeof r->msg; j++)
        len += snprintf(r->msg + len, sizeof r->msg - (size_t)len, " %s",
                        ap_lin_state_name(r->L, j));
      return AP_ERR_ARG;
    }
    r->sel[r->ns++] = s;
  }
  return AP_OK;
}

/* ap_lin_set_poll: about every 0.2 s, take the GIL and let Python run its signal handlers; a
 * handler that raised (KeyboardInterrupt) stops the sweep, its exception left set. */
static int poll_signals(void *user) {
  double *due = user, t = now_s();
  if (t < *due) return 0;
  PyGILState_STATE st = PyGILState_Ensure();
  int raised = PyErr_CheckSignals() != 0;
  PyGILState_Release(st);
  *due = t + 0.2;
  return raised;
}

static int compute(apx_model *m, const char *name, const char *const *sets, int nsets,
                   const lin_args *a, lin_run *r) {
  int rc = ap_scene_lin_guess_load(name, PyBytes_AS_STRING(m->text),
                                   (size_t)PyBytes_GET_SIZE(m->text), sets, nsets, &r->g,
                                   r->msg, sizeof r->msg);
  if (rc != AP_OK) return rc;
  int want_speed = isfinite(a->speed) || a->sweep;
  if (want_speed && !r->g.dir) {
    snprintf(r->msg, sizeof r->msg, "%s: the speed parameter needs linearize.speed (the "
             "initial rates proportional to it) in the scene", name);
    return AP_ERR_ARG;
  }
  ap_lin_def def = ap_scene_lin_def(&r->g);
  if (a->about >= 0) def.about = (ap_lin_about)a->about;
  if (a->free) def.free = a->free;
  if (a->inputs) def.inputs = a->inputs;
  rc = ap_scene_lin_create(&r->g, &def, &r->L);
  double s = isfinite(a->speed) ? a->speed : r->g.speed;   /* NaN without a speed parameter */
  if (rc == AP_OK) rc = ap_lin_operating_point(r->L, a->sweep ? a->sweep[0] : s);
  const char *const *states = a->states ? a->states : (const char *const *)r->g.sec.states;
  int drop = !a->keep_cyclic && r->g.sec.drop_cyclic;
  if (rc == AP_OK && (rc = select_states(r, states)) != AP_OK) return rc;
  double due = now_s() + 0.2;
  if (rc == AP_OK) ap_lin_set_poll(r->L, poll_signals, &due);
  if (rc == AP_OK && a->sweep) {
    rc = ap_lin_sweep_speed(r->L, a->sweep, (int)a->count, r->ns ? r->sel : NULL, r->ns, drop,
                            a->ptol, &r->sw);
    r->swept = rc == AP_OK;
  } else if (rc == AP_OK) {
    rc = ap_lin_linearize(r->L);
    if (rc == AP_OK) rc = ap_lin_eigen(r->L, r->ns ? r->sel : NULL, r->ns, drop);
  }
  if (rc != AP_OK && !r->msg[0] && r->L) snprintf(r->msg, sizeof r->msg, "%s", ap_lin_message(r->L));
  if (r->L) ap_lin_set_poll(r->L, NULL, NULL);
  return rc;
}

/* ---- results as Python objects ------------------------------------------------------------ */

/* A rows x cols float64 array from column-major x. */
static PyObject *matrix(const double *x, int rows, int cols) {
  npy_intp dims[2] = {rows, cols};
  PyObject *a = PyArray_EMPTY(2, dims, NPY_DOUBLE, 1);   /* Fortran order: a plain copy */
  if (a && rows && cols) memcpy(PyArray_DATA((PyArrayObject *)a), x, sizeof *x * (size_t)rows * cols);
  return a;
}

static PyObject *complex_vector(const double *re, const double *im, int n) {
  npy_intp dim = n;
  PyObject *a = PyArray_SimpleNew(1, &dim, NPY_CDOUBLE);
  npy_cdouble *z = a ? PyArray_DATA((PyArrayObject *)a) : NULL;
  for (int i = 0; z && i < n; i++) z[i].real = re[i], z[i].imag = im[i];
  return a;
}

static PyObject *state_names(const ap_lin *L, const int *idx, int n) {
  PyObject *t = PyTuple_New(n);
  for (int i = 0; t && i < n; i++) {
    PyObject *s = PyUnicode_FromString(ap_lin_state_name(L, idx ? idx[i] : i));
    if (!s) return Py_DECREF(t), NULL;
    PyTuple_SET_ITEM(t, i, s);
  }
  return t;
}

/* Right eigenvectors (complex n x n, column j for eigenvalue j) from dgeev's real storage. */
static PyObject *eigenvectors(const ap_lin_eig *e) {
  int n = e->n;
  npy_intp dims[2] = {n, n};
  PyObject *a = PyArray_ZEROS(2, dims, NPY_CDOUBLE, 0);
  npy_cdouble *z = a ? PyArray_DATA((PyArrayObject *)a) : NULL;
  for (int j = 0; z && j < n; j++) {
    int pair = e->im[j] != 0.0, upper = e->im[j] > 0.0;
    const double *re = e->vr + (size_t)(pair && !upper ? j - 1 : j) * n;
    const double *im = pair ? re + n : NULL;
    for (int i = 0; i < n; i++)
      z[(size_t)i * n + j].real = re[i], z[(size_t)i * n + j].imag = im ? (upper ? im[i] : -im[i]) : 0.0;
  }
  return a;
}

static PyObject *point_dict(lin_run *r, double speed) {
  ap_lin *L = r->L;
  int nx = ap_lin_nx(L), nu = ap_lin_nu(L), n = r->g.n, k = r->g.k;
  ap_lin_eig e;
  ap_lin_get_eigen(L, &e);
  PyObject *cyc = PyTuple_New(nx), *inputs = PyTuple_New(nu);
  for (int i = 0; cyc && i < nx; i++) PyTuple_SET_ITEM(cyc, i, PyBool_FromLong(ap_lin_is_cyclic(L, i)));
  for (int j = 0; inputs && j < nu; j++) {
    PyObject *s = PyUnicode_FromString(ap_lin_input_name(L, j));
    if (!s) Py_CLEAR(inputs);
    else PyTuple_SET_ITEM(inputs, j, s);
  }
  PyObject *cyclic = cyc ? PyArray_FROMANY(cyc, NPY_BOOL, 1, 1, 0) : NULL;
  Py_XDECREF(cyc);
  if (!cyclic || !inputs) return Py_XDECREF(cyclic), Py_XDECREF(inputs), NULL;
  return Py_BuildValue(
      "{s:N,s:d,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N,s:N}", "speed",
      isfinite(speed) ? PyFloat_FromDouble(speed) : Py_NewRef(Py_None), "t", r->g.t0, "q",
      apx_vector(ap_lin_q(L), n), "v", apx_vector(ap_lin_v(L), k), "state_names",
      state_names(L, NULL, nx), "cyclic", cyclic, "A", matrix(ap_lin_A(L), nx, nx), "A_error",
      matrix(ap_lin_A_error(L), nx, nx), "B", matrix(ap_lin_B(L), nx, nu), "input_names",
      inputs, "rates", apx_vector(ap_lin_rates(L), nx), "subsystem",
      state_names(L, e.states, e.n), "A_sub", matrix(e.Asub, e.n, e.n), "eigenvalues",
      complex_vector(e.re, e.im, e.n), "rcond", apx_vector(e.rcond, e.n), "rcondv",
      apx_vector(e.rcondv, e.n), "error", apx_vector(e.err, e.n), "eigenvectors",
      eigenvectors(&e));
}

static PyObject *sweep_dict(lin_run *r) {
  const ap_lin_sweep *sw = &r->sw;
  npy_intp dims[2] = {sw->count, sw->n};
  PyObject *ev = PyArray_SimpleNew(2, dims, NPY_CDOUBLE), *pts = PyList_New(0);
  npy_cdouble *z = ev ? PyArray_DATA((PyArrayObject *)ev) : NULL;
  for (size_t i = 0; z && i < (size_t)sw->count * sw->n; i++) z[i].real = sw->re[i], z[i].imag = sw->im[i];
  for (int i = 0; pts && i < sw->npoints; i++) {
    const ap_lin_point *p = &sw->points[i];
    PyObject *d = Py_BuildValue("{s:s,s:d,s:d,s:D,s:i,s:O}", "kind",
                                p->kind == AP_LIN_CROSSING ? "crossing" : "meeting", "p", p->p,
                                "p_err", p->p_err, "value", &(Py_complex){p->re, p->im},
                                "index", p->index, "rising", p->rising ? Py_True : Py_False);
    if (!d || PyList_Append(pts, d)) Py_CLEAR(pts);
    Py_XDECREF(d);
  }
  if (!ev || !pts) return Py_XDECREF(ev), Py_XDECREF(pts), NULL;
  ap_lin_eig e;
  ap_lin_get_eigen(r->L, &e);
  return Py_BuildValue("{s:N,s:N,s:N,s:N}", "p", apx_vector(sw->p, sw->count), "subsystem",
                       state_names(r->L, e.states, e.n), "eigenvalues", ev, "points", pts);
}

/* ---- arguments ---------------------------------------------------------------------------- */

/* None or a tuple of str -> NULL or a NULL-terminated array (into the tuple's items). */
static int names_arg(PyObject *o, PyObject **keep, const char ***out, const char *what) {
  *out = NULL;
  if (!o || o == Py_None) return 0;
  Py_ssize_t n;
  if (!(*keep = apx_str_tuple(o, what))) return -1;
  return (*out = apx_strings(*keep, &n)) ? 0 : -1;
}

static int sweep_arg(PyObject *o, PyArrayObject **keep, lin_args *a) {
  if (!o || o == Py_None) return 0;
  *keep = (PyArrayObject *)PyArray_FROMANY(o, NPY_DOUBLE, 1, 1, NPY_ARRAY_CARRAY_RO);
  if (!*keep) return -1;
  a->sweep = PyArray_DATA(*keep), a->count = PyArray_DIM(*keep, 0);
  for (Py_ssize_t i = 0; i < a->count; i++)
    if (!isfinite(a->sweep[i]) || (i > 0 && !(a->sweep[i] > a->sweep[i - 1]))) {
      PyErr_SetString(PyExc_ValueError, "sweep: the speeds must be finite and ascending");
      return -1;
    }
  if (a->count < 2 || a->count > 1000000) {
    PyErr_Format(PyExc_ValueError, "sweep: 2 to 1000000 speeds, got %zd", a->count);
    return -1;
  }
  if (!(a->ptol > 0))
    a->ptol = 1e-14 * fmax(1.0, fmax(fabs(a->sweep[0]), fabs(a->sweep[a->count - 1])));
  return 0;
}

PyObject *apx_linearize(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"model", "speed", "about", "free", "inputs", "states", "keep_cyclic",
                           "sweep", "ptol", NULL};
  apx_model *m = NULL;
  PyObject *speed = Py_None, *about = Py_None, *fr = NULL, *in = NULL, *st = NULL, *sw = NULL;
  int keep_cyclic = 0;
  lin_args a = {NAN, -1, NULL, NULL, NULL, 0, NULL, 0, 0.0};
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O!|OOOOOpOd", kwlist, &apx_model_type, &m, &speed,
                                   &about, &fr, &in, &st, &keep_cyclic, &sw, &a.ptol))
    return NULL;
  a.keep_cyclic = keep_cyclic;
  if (speed != Py_None) {
    a.speed = PyFloat_AsDouble(speed);
    if (a.speed == -1.0 && PyErr_Occurred()) return NULL;
    if (!isfinite(a.speed)) return PyErr_Format(PyExc_ValueError, "speed must be finite, got %R", speed);
  }
  if (about != Py_None) {
    const char *s = PyUnicode_Check(about) ? PyUnicode_AsUTF8(about) : NULL;
    a.about = s && !strcmp(s, "steady") ? AP_LIN_STEADY : s && !strcmp(s, "equilibrium")
                                                              ? AP_LIN_EQUILIBRIUM : -2;
    if (a.about == -2)
      return PyErr_Format(PyExc_ValueError, "about must be 'steady' or 'equilibrium', got %R", about);
  }
  PyObject *kf = NULL, *ki = NULL, *ks = NULL, *out = NULL;
  PyArrayObject *kp = NULL;
  Py_ssize_t nsets = 0;
  const char **sets = NULL;
  lin_run *r = NULL;
  const char *name = PyUnicode_AsUTF8(m->name);
  if (!name || names_arg(fr, &kf, &a.free, "free") || names_arg(in, &ki, &a.inputs, "inputs") ||
      names_arg(st, &ks, &a.states, "states") || sweep_arg(sw, &kp, &a) ||
      !(sets = apx_strings(m->sets, &nsets)))
    goto done;
  if (!(r = PyMem_Calloc(1, sizeof *r))) {
    PyErr_NoMemory();
    goto done;
  }
  int rc;
  Py_BEGIN_ALLOW_THREADS   /* m's text, name and sets and the argument tuples stay alive */
  rc = compute(m, name, sets, (int)nsets, &a, r);
  Py_END_ALLOW_THREADS
  if (rc == AP_ERR_INTERRUPTED && PyErr_Occurred()) {}   /* the handler's exception */
  else if (rc != AP_OK) apx_raise(rc, r->msg);
  else out = a.sweep ? sweep_dict(r) : point_dict(r, isfinite(a.speed) ? a.speed : r->g.speed);
done:
  if (r) {
    if (r->swept) ap_lin_sweep_free(&r->sw);
    ap_lin_free(r->L);
    ap_scene_lin_guess_free(&r->g);
    PyMem_Free(r);
  }
  PyMem_Free(sets);
  PyMem_Free((void *)a.free), PyMem_Free((void *)a.inputs), PyMem_Free((void *)a.states);
  Py_XDECREF(kf), Py_XDECREF(ki), Py_XDECREF(ks), Py_XDECREF(kp);
  return out;
}
