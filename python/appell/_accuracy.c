/* Accuracy on demand for the appell package (docs/accuracy.md, include/appell/accuracy.h):
 *
 *   _error_estimate(model, settings, t0, q0, v0, table) -> dict: the global error of a run's
 *       rows (table: rows x columns, column 0 = t, the first row at t0) by a reference run
 *       through the same times (ap_error_against).
 *   _pick(model, accuracy, settings, t0, q0, v0, t_end, dt) -> dict: ap_accuracy_pick for the
 *       rows at t0 + i dt up to t_end.
 *
 * settings is Simulation.settings (mode, method, rtol, atol, h_fixed, h_init, h_max,
 * max_steps). Each simulation the library makes gets the scene's events and its own output
 * evaluator, whose first row is taken at t0 (E(t0), angle unwrapping), as Simulation.run
 * does. The integrations run with the GIL released. */
#include "_ext.h"

#include <math.h>
#include <string.h>

typedef struct acc_ctx {
  ap_scene *sc;
  ap_scene_out *out;
  double *scratch;         /* (nc) the row at t0 */
} acc_ctx;

static int acc_setup(ap_sim *s, void *user) {
  acc_ctx *c = user;
  ap_scene_out_free(c->out);
  c->out = NULL;
  int rc = ap_scene_add_events(c->sc, s, NULL, 0);
  if (rc == AP_OK) rc = ap_scene_out_create(c->sc, &c->out);
  if (rc == AP_OK) rc = ap_scene_out_row(c->out, s, c->scratch);
  return rc;
}

static int acc_out(ap_sim *s, double *row, void *user) {
  return ap_scene_out_row(((acc_ctx *)user)->out, s, row);
}

static const char *const modes[] = {"minimal", "projected", "dae", "plain", NULL};

/* settings (a dict) over the scene's simulation settings into *d; the method string lives in
 * the dict. -1 with an exception set. */
static int take_settings(PyObject *set, ap_sim_def *d) {
  if (!PyDict_Check(set)) return PyErr_SetString(PyExc_TypeError, "settings must be a dict"), -1;
  PyObject *mode = PyDict_GetItemString(set, "mode"), *meth = PyDict_GetItemString(set, "method");
  const char *ms = mode && PyUnicode_Check(mode) ? PyUnicode_AsUTF8(mode) : NULL;
  for (int i = 0; ms && modes[i]; i++)
    if (strcmp(ms, modes[i]) == 0) d->mode = (ap_mode)i;
  if (meth && PyUnicode_Check(meth)) d->method = PyUnicode_AsUTF8(meth);
  static const char *const keys[6] = {"rtol", "atol", "h_fixed", "h_init", "h_max", "max_steps"};
  double *field[5] = {&d->rtol, &d->atol, &d->h_fixed, &d->h_init, &d->h_max};
  for (int i = 0; i < 6; i++) {
    PyObject *x = PyDict_GetItemString(set, keys[i]);
    if (!x) continue;
    double v = PyFloat_AsDouble(x);
    if (v == -1.0 && PyErr_Occurred()) return -1;
    if (i < 5) *field[i] = v;
    else d->max_steps = (long)v;
  }
  return 0;
}

/* A C-contiguous float64 copy of o with the given number of dimensions (NULL: error set). */
static PyArrayObject *array(PyObject *o, int nd) {
  return (PyArrayObject *)PyArray_FROMANY(o, NPY_DOUBLE, nd, nd, NPY_ARRAY_CARRAY_RO);
}

static PyObject *reference_dict(const ap_error_report *rep) {
  return Py_BuildValue("{s:s,s:d,s:d,s:l,s:l}", "method", rep->ref.method, "rtol",
                       rep->ref.rtol, "atol", rep->ref.atol, "steps", rep->ref_stats.steps,
                       "evaluations", rep->ref_stats.rhs_evals);
}

PyObject *apx_error_estimate(PyObject *self, PyObject *args) {
  (void)self;
  PyObject *model, *set, *q0o, *v0o, *tab;
  double t0;
  if (!PyArg_ParseTuple(args, "O!OdOOO", &apx_model_type, &model, &set, &t0, &q0o, &v0o, &tab))
    return NULL;
  ap_scene *sc = ((apx_model *)model)->sc;
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  if (take_settings(set, &run.sim)) return NULL;
  PyArrayObject *q0 = array(q0o, 1), *v0 = q0 ? array(v0o, 1) : NULL, *T = v0 ? array(tab, 2) : NULL;
  PyObject *res = NULL;
  int nc = ap_scene_output_count(sc);
  if (!T) goto done;
  npy_intp nr = PyArray_DIM(T, 0);
  if (PyArray_DIM(T, 1) != nc || nr < 2 || PyArray_DIM(q0, 0) != ap_model_n(ap_scene_model(sc)) ||
      PyArray_DIM(v0, 0) != ap_model_k(ap_scene_model(sc))) {
    PyErr_SetString(PyExc_ValueError, "_error_estimate: table, q0 or v0 of the wrong shape");
    goto done;
  }
  const double *rows = PyArray_DATA(T);
  npy_intp dims[2] = {nr, nc};
  PyArrayObject *E = (PyArrayObject *)PyArray_ZEROS(2, dims, NPY_DOUBLE, 0);
  double *times = PyMem_Calloc((size_t)nr * (size_t)(nc + 1) + (size_t)nc, sizeof *times);
  if (!E || !times) {
    Py_XDECREF(E), PyMem_Free(times), PyErr_NoMemory();
    goto done;
  }
  double *ref = times + nr, *e = PyArray_DATA(E);
  for (npy_intp i = 1; i < nr; i++) times[i - 1] = rows[i * nc];
  acc_ctx c = {sc, NULL, ref + (size_t)nr * (size_t)nc};
  ap_error_report rep;
  char msg[1024];
  int rc;
  Py_BEGIN_ALLOW_THREADS
  rc = ap_error_against(ap_scene_model(sc), &run.sim, t0, PyArray_DATA(q0), PyArray_DATA(v0),
                        times, (int)nr - 1, nc, acc_out, acc_setup, &c, rows + nc, ref, NULL,
                        NULL, &rep, msg, sizeof msg);
  Py_END_ALLOW_THREADS
  ap_scene_out_free(c.out);
  for (npy_intp i = 0; rc == AP_OK && i < nr; i++)
    for (int k = 0; k < nc; k++)
      e[i * nc + k] = k == 0 ? rows[i * nc] : i == 0 ? 0.0
                    : fabs(rows[i * nc + k] - ref[(i - 1) * nc + k]);
  PyMem_Free(times);
  if (rc != AP_OK) {
    Py_DECREF(E);
    apx_raise(rc, msg);
    goto done;
  }
  res = Py_BuildValue("{s:d,s:O,s:N,s:N}", "error", rep.error, "reliable",
                      rep.reliable ? Py_True : Py_False, "errors", (PyObject *)E, "reference",
                      reference_dict(&rep));
done:
  Py_XDECREF(q0), Py_XDECREF(v0), Py_XDECREF(T);
  return res;
}

PyObject *apx_pick(PyObject *self, PyObject *args) {
  (void)self;
  PyObject *model, *set, *q0o, *v0o;
  double acc, t0, t_end, dt;
  if (!PyArg_ParseTuple(args, "O!dOdOOdd", &apx_model_type, &model, &acc, &set, &t0, &q0o, &v0o,
                        &t_end, &dt))
    return NULL;
  if (!(dt > 0) || !(t_end > t0) || (t_end - t0) / dt > 1e7)
    return PyErr_SetString(PyExc_ValueError, "accuracy: the output times need t_end > t0 and "
                           "0 < dt, at most 1e7 rows"), NULL;
  ap_scene *sc = ((apx_model *)model)->sc;
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  if (take_settings(set, &run.sim)) return NULL;
  PyArrayObject *q0 = array(q0o, 1), *v0 = q0 ? array(v0o, 1) : NULL;
  PyObject *res = NULL;
  long nt = (long)ceil((t_end - t0) / dt - 1e-9);
  if (nt < 1) nt = 1;
  int nc = ap_scene_output_count(sc);
  double *times = v0 ? PyMem_Calloc((size_t)nt + (size_t)nc + 1, sizeof *times) : NULL;
  if (v0 && !times) PyErr_NoMemory();
  if (!times) goto done;
  for (long i = 1; i <= nt; i++) times[i - 1] = i == nt ? t_end : t0 + (double)i * dt;
  acc_ctx c = {sc, NULL, times + nt};
  ap_pick_report pk;
  char msg[1024];
  int rc;
  Py_BEGIN_ALLOW_THREADS
  rc = ap_accuracy_pick(ap_scene_model(sc), &run.sim, t0, PyArray_DATA(q0), PyArray_DATA(v0),
                        times, (int)nt, nc, acc_out, acc_setup, &c, acc, &pk, msg, sizeof msg);
  Py_END_ALLOW_THREADS
  ap_scene_out_free(c.out);
  PyMem_Free(times);
  if (rc != AP_OK) apx_raise(rc, msg);
  else res = Py_BuildValue("{s:d,s:s,s:d,s:d,s:d,s:l,s:l,s:l}", "accuracy", acc, "method",
                           pk.def.method, "rtol", pk.def.rtol, "atol", pk.def.atol,
                           "estimated_error", pk.estimated_error, "evaluations", pk.evals,
                           "pilot_evaluations", pk.pilot_evals, "check_evaluations",
                           pk.verify_evals);
done:
  Py_XDECREF(q0), Py_XDECREF(v0);
  return res;
}
