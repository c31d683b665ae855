/* appell Simulation: one simulation (ap_sim) of a Model, with its own output evaluator
 * (ap_scene_out), so that simulations of one Model run in parallel Python threads.
 *
 * _run(t_end, dt) records rows at t, t + dt, ..., t_end (the last exactly t_end) from the
 * current time, as `appell run` writes them: the output columns (table), q and v. The arrays
 * are allocated first; the integration then runs with the GIL released, taking it back about
 * every 0.2 s (between internal steps, through ap_sim_set_poll) to let Python handle signals:
 * Ctrl-C stops the run where it is, even inside one long output interval. A failure raises
 * appell.Error, and a signal its handler's exception (KeyboardInterrupt), with .partial =
 * (columns, table, q, v) up to the last time reached.
 * Invariant: at most one thread works on a Simulation at a time (busy), and the Simulation
 * holds a reference to its Model, so the scene outlives the simulation.
 * While it is busy, other threads read state, t, stats and warning from a snapshot (snap), not
 * from the simulation the worker is changing without the GIL: the snapshot is taken with the
 * GIL held while the worker is between internal steps (when the run starts and whenever it
 * takes the GIL back, about every 0.2 s), so t, q and v always belong to one step. */
#include "_ext.h"

#include <math.h>
#include <string.h>
#include <time.h>

typedef struct apx_sim {
  PyObject_HEAD
  apx_model *model;
  ap_sim *sim;
  ap_scene_out *out;
  ap_scene_run run;        /* the settings in use (method points into `method`) */
  char method[32];
  PyObject *report;        /* str: corrections of the initial state */
  int busy;
  double *snap;            /* while busy: t, q (n), v (k) of the last snapshot */
  ap_sim_stats snap_stats;
  PyObject *snap_warning;  /* str */
  PyObject *snap_events;   /* list of the events recorded by the snapshot */
} apx_sim;

static const char *const mode_names[] = {"minimal", "projected", "dae", "plain", NULL};

static int parse_mode(PyObject *o, ap_mode *mode) {
  const char *s = PyUnicode_Check(o) ? PyUnicode_AsUTF8(o) : NULL;
  for (int i = 0; s && mode_names[i]; i++)
    if (strcmp(s, mode_names[i]) == 0) return *mode = (ap_mode)i, 0;
  PyErr_Format(PyExc_ValueError, "mode must be one of minimal, projected, dae, plain; got %R", o);
  return -1;
}

/* Keyword settings over the scene's. */
static int apply_settings(apx_sim *s, PyObject *mode, PyObject *method, PyObject *num[6]) {
  static const char *const names[6] = {"rtol", "atol", "h_fixed", "h_init", "h_max", "max_steps"};
  ap_sim_def *d = &s->run.sim;
  snprintf(s->method, sizeof s->method, "%s", d->method ? d->method : "dopri5");
  if (mode && mode != Py_None && parse_mode(mode, &d->mode)) return -1;
  if (method && method != Py_None) {
    const char *m = PyUnicode_Check(method) ? PyUnicode_AsUTF8(method) : NULL;
    ap_method_info info;
    if (!m || ap_method_find(m, &info) != AP_OK) {
      PyErr_Format(PyExc_ValueError, "unknown method %R (appell.methods() lists them)", method);
      return -1;
    }
    snprintf(s->method, sizeof s->method, "%s", m);
  }
  d->method = s->method;
  double *field[6] = {&d->rtol, &d->atol, &d->h_fixed, &d->h_init, &d->h_max, NULL};
  for (int i = 0; i < 6; i++) {
    if (!num[i] || num[i] == Py_None) continue;
    double x = PyFloat_AsDouble(num[i]);
    if (x == -1.0 && PyErr_Occurred()) return -1;
    if (!isfinite(x) || x < 0 || (i < 2 && x == 0)) {
      PyErr_Format(PyExc_ValueError, "%s must be a finite number > 0, got %R", names[i], num[i]);
      return -1;
    }
    if (!field[i] && !(x >= 1 && x == floor(x) && x < 0x1p62)) {   /* (long)x must be exact */
      PyErr_Format(PyExc_ValueError, "max_steps must be a whole number >= 1, got %R", num[i]);
      return -1;
    }
    if (field[i]) *field[i] = x;
    else d->max_steps = (long)x;
  }
  return 0;
}

/* q0 or v0 given as a sequence of len floats, over the scene's initial state. */
static int take_vector(PyObject *o, double *x, int len, const char *what) {
  if (!o || o == Py_None) return 0;
  PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(o, NPY_DOUBLE, 1, 1, NPY_ARRAY_CARRAY_RO);
  if (!a) return -1;
  int ok = PyArray_DIM(a, 0) == len;
  if (ok) memcpy(x, PyArray_DATA(a), sizeof(double) * (size_t)len);
  else PyErr_Format(PyExc_ValueError, "%s must have %d entries, got %zd", what, len,
                    (Py_ssize_t)PyArray_DIM(a, 0));
  Py_DECREF(a);
  return ok ? 0 : -1;
}

static int start(apx_sim *s, PyObject *q0, PyObject *v0, PyObject *t0) {
  const ap_model *m = ap_scene_model(s->model->sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double *q = PyMem_Calloc((size_t)(n + k) + 1, sizeof *q), t = s->run.t0;
  if (!q) return PyErr_NoMemory(), -1;
  char report[2048] = "", msg[1024];
  int rc = ap_scene_initial_state(s->model->sc, q, q + n, report, sizeof report, msg, sizeof msg);
  if (rc != AP_OK) apx_raise_input(rc, msg);
  if (t0 && t0 != Py_None) t = PyFloat_AsDouble(t0);
  if (rc == AP_OK && !PyErr_Occurred() && !take_vector(q0, q, n, "q0") &&
      !take_vector(v0, q + n, k, "v0")) {
    rc = ap_sim_create(m, &s->run.sim, t, q, q + n, &s->sim, msg, sizeof msg);
    if (rc == AP_OK) rc = ap_scene_add_events(s->model->sc, s->sim, msg, sizeof msg);
    if (rc != AP_OK) apx_raise(rc, msg);
    else if (ap_scene_out_create(s->model->sc, &s->out) != AP_OK) PyErr_NoMemory();
    else if (!(s->snap = PyMem_Calloc((size_t)(n + k) + 1, sizeof *s->snap))) PyErr_NoMemory();
    else s->report = PyUnicode_FromString(report);
  }
  PyMem_Free(q);
  return PyErr_Occurred() ? -1 : 0;
}

static PyObject *sim_new(PyTypeObject *type, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"model", "mode", "method", "rtol", "atol", "h_fixed", "h_init",
                           "h_max", "max_steps", "t0", "q0", "v0", NULL};
  PyObject *model = NULL, *mode = NULL, *method = NULL, *num[6] = {0}, *t0 = NULL, *q0 = NULL,
           *v0 = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O!|$OOOOOOOOOOO", kwlist, &apx_model_type, &model,
                                   &mode, &method, &num[0], &num[1], &num[2], &num[3], &num[4],
                                   &num[5], &t0, &q0, &v0))
    return NULL;
  apx_sim *s = (apx_sim *)type->tp_alloc(type, 0);
  if (!s) return NULL;
  s->model = (apx_model *)Py_NewRef(model);
  ap_scene_get_run(s->model->sc, &s->run);
  if (apply_settings(s, mode, method, num) || start(s, q0, v0, t0)) return Py_DECREF(s), NULL;
  return (PyObject *)s;
}

static void sim_dealloc(apx_sim *s) {
  ap_scene_out_free(s->out);
  ap_sim_free(s->sim);
  PyMem_Free(s->snap);
  Py_XDECREF(s->snap_warning);
  Py_XDECREF(s->snap_events);
  Py_XDECREF(s->report);
  Py_XDECREF(s->model);
  Py_TYPE(s)->tp_free((PyObject *)s);
}

/* The snapshot other threads read while s is busy. Called with the GIL held, while the
 * simulation is between internal steps. */
static void take_snapshot(apx_sim *s) {
  const ap_model *m = ap_scene_model(s->model->sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  s->snap[0] = ap_sim_time(s->sim);
  memcpy(s->snap + 1, ap_sim_q(s->sim), sizeof(double) * (size_t)n);
  memcpy(s->snap + 1 + n, ap_sim_v(s->sim), sizeof(double) * (size_t)k);
  ap_sim_get_stats(s->sim, &s->snap_stats);
  PyObject *w = PyUnicode_FromString(ap_sim_warning(s->sim));
  if (w) Py_XSETREF(s->snap_warning, w);
  else PyErr_Clear();   /* out of memory: the previous warning stays */
  PyObject *ev = apx_events(s->sim);
  if (ev) Py_XSETREF(s->snap_events, ev);
  else PyErr_Clear();   /* out of memory: the previous list stays */
}

static int claim(apx_sim *s) {
  if (!s->busy) return take_snapshot(s), s->busy = 1, 0;
  PyErr_SetString(PyExc_RuntimeError, "this Simulation is running in another thread");
  return -1;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- recording ------------------------------------------------------------------------- */

typedef struct rec {
  double *table, *q, *v;   /* array data: (rows x nc), (rows x n), (rows x k) */
  int nc, n, k;
  long rows, done;         /* rows wanted, rows written */
  int rc, interrupted;
  double tout;             /* the output time of the last advance (NaN before any) */
} rec;

static int record(apx_sim *s, rec *r) {
  int rc = ap_scene_out_row(s->out, s->sim, r->table + (size_t)r->done * (size_t)r->nc);
  if (rc != AP_OK) return rc;
  memcpy(r->q + (size_t)r->done * (size_t)r->n, ap_sim_q(s->sim), sizeof(double) * (size_t)r->n);
  memcpy(r->v + (size_t)r->done * (size_t)r->k, ap_sim_v(s->sim), sizeof(double) * (size_t)r->k);
  r->done++;
  return AP_OK;
}

/* ap_sim_poll_fn: stop an advance when the next look at Python's signals is due. */
static int poll_due(double t, void *user) {
  (void)t;
  return now() > *(const double *)user;
}

/* Advance to t with the GIL released; about every 0.2 s (between internal steps, through the
 * poll) take the GIL back to let Python run its signal handlers. Returns the status; sets
 * *interrupted when a handler raised (KeyboardInterrupt). Called without the GIL. */
static int advance_released(apx_sim *s, double t, double *due, int *interrupted,
                            PyThreadState **ts) {
  int rc;
  ap_sim_set_poll(s->sim, poll_due, due);
  do {
    rc = ap_sim_advance(s->sim, t);
    if (rc == AP_ERR_INTERRUPTED || now() > *due) {
      PyEval_RestoreThread(*ts);
      take_snapshot(s);
      *interrupted = PyErr_CheckSignals() != 0;
      *ts = PyEval_SaveThread();
      *due = now() + 0.2;
    }
  } while (rc == AP_ERR_INTERRUPTED && !*interrupted);
  ap_sim_set_poll(s->sim, NULL, NULL);
  return rc;
}

/* The most rows one run() records: the scene loader's limit on (t_end - t0) / output.interval
 * (lib/scene/parse_run.c), which appell run therefore obeys too. */
#define APX_MAX_ROWS 1e7

/* Rows at t0 + i dt (the last at t_end), with the GIL released. */
static void record_rows(apx_sim *s, rec *r, double t0, double t_end, double dt) {
  double due = now() + 0.2;
  PyThreadState *ts = PyEval_SaveThread();
  r->rc = record(s, r);
  for (long i = 1; r->rc == AP_OK && !r->interrupted && i < r->rows; i++) {
    double t = i == r->rows - 1 ? t_end : t0 + (double)i * dt;
    r->tout = t;
    r->rc = advance_released(s, t, &due, &r->interrupted, &ts);
    if (r->rc == AP_STOPPED) {   /* a stop event: its row is the last */
      r->rc = record(s, r);
      break;
    }
    if (r->rc == AP_OK) r->rc = record(s, r);
  }
  /* Stopped by a signal: a last row where it stopped, as appell run writes (an interrupted
   * advance leaves q and v at that step; a failed one may not, so a failure gets none). */
  if (r->interrupted && r->done > 0 && r->done < r->rows &&
      ap_sim_time(s->sim) > r->table[(size_t)(r->done - 1) * (size_t)r->nc])
    record(s, r);
  PyEval_RestoreThread(ts);
  if (r->interrupted && r->rc == AP_ERR_INTERRUPTED) r->rc = AP_OK;   /* the signal wins */
}

/* (columns, table, q, v) with the first `done` rows. */
static PyObject *result(apx_sim *s, PyArrayObject *arr[3], long done) {
  PyObject *cols = PyTuple_New(ap_scene_output_count(s->model->sc));
  for (int i = 0; cols && i < (int)PyTuple_GET_SIZE(cols); i++) {
    PyObject *name = PyUnicode_FromString(ap_scene_output_name(s->model->sc, i));
    if (!name) return Py_DECREF(cols), NULL;
    PyTuple_SET_ITEM(cols, i, name);
  }
  PyObject *t[3] = {NULL, NULL, NULL}, *stop = PyLong_FromLong(done);
  PyObject *slice = stop ? PySlice_New(NULL, stop, NULL) : NULL;
  for (int i = 0; slice && i < 3; i++) t[i] = PyObject_GetItem((PyObject *)arr[i], slice);
  Py_XDECREF(slice);
  Py_XDECREF(stop);
  return cols && t[0] && t[1] && t[2] ? Py_BuildValue("(NNNN)", cols, t[0], t[1], t[2])
                                      : (Py_XDECREF(cols), Py_XDECREF(t[0]), Py_XDECREF(t[1]),
                                         Py_XDECREF(t[2]), NULL);
}

/* The exception being raised (a failure's Error, or the KeyboardInterrupt of a signal) gets
 * .partial = (columns, table, q, v): the rows recorded up to where the run stopped. */
static PyObject *attach_partial(apx_sim *s, rec *r, PyArrayObject *arr[3]) {
  PyObject *type, *value, *tb;
  PyErr_Fetch(&type, &value, &tb);
  PyObject *partial = result(s, arr, r->done);
  PyErr_Clear();   /* a failure to build it leaves the original exception */
  PyErr_NormalizeException(&type, &value, &tb);
  if (partial && value) PyObject_SetAttrString(value, "partial", partial);
  PyErr_Clear();
  Py_XDECREF(partial);
  PyErr_Restore(type, value, tb);
  return NULL;
}

static PyObject *failed(apx_sim *s, rec *r, PyArrayObject *arr[3]) {
  char msg[2600];
  apx_run_message(s->model->sc, s->sim, r->rc, r->tout, msg, sizeof msg);
  apx_raise(r->rc, msg);
  return attach_partial(s, r, arr);
}

static PyObject *sim_run(apx_sim *s, PyObject *args, PyObject *kw) {
  static char *kwlist[] = {"t_end", "dt", NULL};
  PyObject *te = Py_None, *dto = Py_None;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "|OO", kwlist, &te, &dto)) return NULL;
  double t0 = ap_sim_time(s->sim);
  double t_end = te == Py_None ? s->run.t_end : PyFloat_AsDouble(te);
  double dt = dto == Py_None ? s->run.interval : PyFloat_AsDouble(dto);
  if (PyErr_Occurred()) return NULL;
  if (!(t_end >= t0) || !isfinite(t_end) || !(dt > 0) || !isfinite(dt)) {
    char msg[160];   /* PyErr_Format has no %g */
    snprintf(msg, sizeof msg, "need t_end >= the current time %.17g and dt > 0 (got t_end = "
             "%.17g, dt = %.17g)", t0, t_end, dt);
    PyErr_SetString(PyExc_ValueError, msg);
    return NULL;
  }
  double nrows = ceil((t_end - t0) / dt - 1e-9) + 1;   /* may be Inf: dt = 1e-300 */
  if (!(nrows <= APX_MAX_ROWS + 1)) {
    char msg[240];
    snprintf(msg, sizeof msg, "run(t_end=%.17g, dt=%.17g) would record %.3g rows, more than "
             "the 10^7 output rows a scene allows (output.interval): use a larger dt or "
             "advance() in steps", t_end, dt, nrows);
    PyErr_SetString(PyExc_ValueError, msg);
    return NULL;
  }
  const ap_model *m = ap_scene_model(s->model->sc);
  rec r = {NULL, NULL, NULL, ap_scene_output_count(s->model->sc), ap_model_n(m), ap_model_k(m),
           0, 0, AP_OK, 0, NAN};
  r.rows = (long)nrows;
  if (r.rows < (t_end > t0 ? 2 : 1)) r.rows = t_end > t0 ? 2 : 1;   /* dt past t_end: t0, t_end */
  npy_intp d0[2] = {r.rows, r.nc}, d1[2] = {r.rows, r.n}, d2[2] = {r.rows, r.k};
  PyArrayObject *arr[3] = {(PyArrayObject *)PyArray_ZEROS(2, d0, NPY_DOUBLE, 0),
                           (PyArrayObject *)PyArray_ZEROS(2, d1, NPY_DOUBLE, 0),
                           (PyArrayObject *)PyArray_ZEROS(2, d2, NPY_DOUBLE, 0)};
  PyObject *out = NULL;
  if (arr[0] && arr[1] && arr[2] && !claim(s)) {
    r.table = PyArray_DATA(arr[0]), r.q = PyArray_DATA(arr[1]), r.v = PyArray_DATA(arr[2]);
    record_rows(s, &r, t0, t_end, dt);
    s->busy = 0;
    if (r.interrupted) out = attach_partial(s, &r, arr);   /* the handler's exception */
    else if (r.rc != AP_OK) out = failed(s, &r, arr);
    else out = result(s, arr, r.done);
  }
  for (int i = 0; i < 3; i++) Py_XDECREF(arr[i]);
  return out;
}

static PyObject *sim_advance(apx_sim *s, PyObject *arg) {
  double t = PyFloat_AsDouble(arg);
  if (t == -1.0 && PyErr_Occurred()) return NULL;
  if (!(t >= ap_sim_time(s->sim)) || !isfinite(t)) {
    char msg[120];   /* PyErr_Format has no %g */
    snprintf(msg, sizeof msg, "advance(t): t must be finite and >= the current time %.17g "
             "(got %.17g)", ap_sim_time(s->sim), t);
    PyErr_SetString(PyExc_ValueError, msg);
    return NULL;
  }
  if (claim(s)) return NULL;
  double due = now() + 0.2;
  int interrupted = 0;
  PyThreadState *ts = PyEval_SaveThread();
  int rc = advance_released(s, t, &due, &interrupted, &ts);
  PyEval_RestoreThread(ts);
  s->busy = 0;
  if (interrupted) return NULL;   /* the handler's exception (KeyboardInterrupt) is set */
  if (rc == AP_OK || rc == AP_STOPPED) Py_RETURN_NONE;   /* stopped: see .events */
  char msg[2600];
  apx_run_message(s->model->sc, s->sim, rc, t, msg, sizeof msg);
  return apx_raise(rc, msg);
}

/* ---- state and statistics -------------------------------------------------------------- */

/* Readers: the simulation itself, or the snapshot while another thread integrates it. */
static PyObject *get_state(apx_sim *s, void *c) {
  (void)c;
  const ap_model *m = ap_scene_model(s->model->sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  if (s->busy)
    return Py_BuildValue("(dNN)", s->snap[0], apx_vector(s->snap + 1, n),
                         apx_vector(s->snap + 1 + n, k));
  return Py_BuildValue("(dNN)", ap_sim_time(s->sim), apx_vector(ap_sim_q(s->sim), n),
                       apx_vector(ap_sim_v(s->sim), k));
}

static PyObject *get_time(apx_sim *s, void *c) {
  (void)c;
  return PyFloat_FromDouble(s->busy ? s->snap[0] : ap_sim_time(s->sim));
}

static PyObject *get_stats(apx_sim *s, void *c) {
  (void)c;
  ap_sim_stats st = s->snap_stats;
  if (!s->busy) ap_sim_get_stats(s->sim, &st);
  return Py_BuildValue("{s:l,s:l,s:l,s:l,s:l,s:l,s:l,s:d,s:d,s:d,s:d,s:d}", "steps", st.steps,
                       "rhs_evals", st.rhs_evals, "err_fails", st.err_fails, "rhs_fails",
                       st.rhs_fails, "partition_switches", st.partition_switches, "projections",
                       st.projections, "restarts", st.restarts, "max_residual", st.max_residual,
                       "max_projection", st.max_projection, "init_correction",
                       st.init_correction, "min_rcond", st.min_rcond, "max_phi", st.max_phi);
}

static PyObject *get_warning(apx_sim *s, void *c) {
  (void)c;
  if (s->busy && s->snap_warning) return Py_NewRef(s->snap_warning);
  return PyUnicode_FromString(ap_sim_warning(s->sim));
}

static PyObject *get_events(apx_sim *s, void *c) {
  (void)c;
  if (s->busy && s->snap_events) return Py_NewRef(s->snap_events);
  return apx_events(s->sim);
}

static PyObject *get_report(apx_sim *s, void *c) {
  (void)c;
  return Py_NewRef(s->report);
}

static PyObject *get_model(apx_sim *s, void *c) {
  (void)c;
  return Py_NewRef((PyObject *)s->model);
}

static PyObject *get_settings(apx_sim *s, void *c) {
  (void)c;
  const ap_sim_def *d = &s->run.sim;
  return Py_BuildValue("{s:s,s:s,s:d,s:d,s:d,s:d,s:d,s:l}", "mode", mode_names[d->mode % 4],
                       "method", d->method, "rtol", d->rtol, "atol", d->atol, "h_fixed",
                       d->h_fixed, "h_init", d->h_init, "h_max", d->h_max, "max_steps",
                       d->max_steps);
}

static PyGetSetDef sim_getset[] = {
    {"state", (getter)get_state, NULL, "(t, q, v) now (copies); while another thread runs it, "
     "those of one step of the last snapshot (about every 0.2 s)", NULL},
    {"t", (getter)get_time, NULL, "the current time (while running: the snapshot's)", NULL},
    {"stats", (getter)get_stats, NULL, "step counts, residuals, conditioning (a dict; while "
     "running: the snapshot's)", NULL},
    {"warning", (getter)get_warning, NULL, "the run's first warning, or '' (while running: the "
     "snapshot's)", NULL},
    {"events", (getter)get_events, NULL, "the events recorded so far (a list of dicts; while "
     "running: the snapshot's)", NULL},
    {"report", (getter)get_report, NULL, "corrections made to the initial state, or ''", NULL},
    {"model", (getter)get_model, NULL, "the Model simulated", NULL},
    {"settings", (getter)get_settings, NULL, "mode, method and tolerances in use", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyMethodDef sim_methods[] = {
    {"_run", (PyCFunction)(void (*)(void))sim_run, METH_VARARGS | METH_KEYWORDS,
     "_run(t_end=None, dt=None) -> (columns, table, q, v); appell.Simulation.run wraps it"},
    {"advance", (PyCFunction)sim_advance, METH_O,
     "advance(t): integrate to time t without recording (the GIL is released)"},
    {NULL, NULL, 0, NULL}};

PyTypeObject apx_sim_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "appell._appell.Simulation",
    .tp_basicsize = sizeof(apx_sim),
    .tp_dealloc = (destructor)sim_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "Simulation(model, mode=, method=, rtol=, atol=, ...): one run of a Model.",
    .tp_new = sim_new,
    .tp_getset = sim_getset,
    .tp_methods = sim_methods,
};

/* ---- for _ctrl.c (inputs and controllers) ---------------------------------------------- */

ap_sim *apx_sim_handle(PyObject *obj, const ap_scene **sc, int idle) {
  if (!PyObject_TypeCheck(obj, &apx_sim_type))
    return PyErr_SetString(PyExc_TypeError, "expected an appell.Simulation"), NULL;
  apx_sim *s = (apx_sim *)obj;
  if (idle && s->busy)
    return PyErr_SetString(PyExc_RuntimeError, "this Simulation is running in another thread"),
           NULL;
  if (sc) *sc = s->model->sc;
  return s->sim;
}
