/* Inputs and controllers in the loop from Python (docs/control.md; C API appell/control.h).
 *
 * _set_controller(sim, f, period) puts a C trampoline on the simulation (ap_sim_set_controller)
 * and returns a handle (a capsule) that owns what the trampoline reads: f, the names of the
 * state, an output evaluator of the scene. The integration runs with the GIL released
 * (_sim.c); the trampoline takes the GIL only to call f(t, state), state a dict of every
 * coordinate, speed and output column by name (channels included) plus "q" and "v" arrays,
 * and converts the result (a dict by input name, or a sequence of one value per input) into
 * the inputs, held until the next call. An exception raised by f (or a bad result) is kept in
 * the handle and the trampoline returns -1: the advance stops with AP_ERR_CALLBACK, and
 * Simulation.run re-raises the kept exception with the partial result.
 * Invariant: the simulation's controller points to a live handle: Simulation.run removes it
 * (_set_controller(sim, None, 0)) before it drops the handle.
 * The scene's inputs: are declared on the simulation the first time they are needed. */
#include "_ext.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct apx_ctrl {
  PyObject *f;             /* the controller */
  PyObject *simobj;        /* the Simulation (a reference: it outlives the handle's use) */
  ap_sim *sim;
  ap_scene_out *out;       /* the scene's output columns, evaluated at each call */
  PyObject *keys;          /* tuple: coordinate names (n), speed names (k), columns (nc) */
  PyObject *key_q, *key_v; /* "q", "v" */
  double *row;             /* (nc) */
  int n, k, nc;
  PyObject *exc;           /* what f raised (normalized, with its traceback), or NULL */
} apx_ctrl;

#define APX_CTRL_CAPSULE "appell.controller"

/* The scene's inputs declared on sim when it has none yet; 0, or -1 with an exception. */
static int ensure_inputs(ap_sim *sim, const ap_scene *sc) {
  char msg[1024] = "";
  int rc = ap_sim_input_count(sim) ? AP_OK : ap_scene_add_inputs(sc, sim, msg, sizeof msg);
  if (rc != AP_OK) return apx_raise(rc, msg), -1;
  if (ap_sim_input_count(sim) > 0) return 0;
  PyErr_SetString(PyExc_ValueError, "the scene declares no inputs: list the speeds that "
                  "receive a force or torque in an inputs: section (docs/control.md)");
  return -1;
}

/* One value of an input, by name, into u; 0 or -1 with an exception. */
static int take_named(ap_sim *sim, PyObject *key, PyObject *val, double *u) {
  const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
  int j = name ? ap_sim_find_input(sim, name) : -1;
  if (j < 0) {
    if (!PyErr_Occurred())
      PyErr_Format(PyExc_KeyError, "no input %R; the inputs are %s%s", key,
                   ap_sim_input_name(sim, 0), ap_sim_input_count(sim) > 1 ? ", ..." : "");
    return -1;
  }
  double x = PyFloat_AsDouble(val);
  if (x == -1.0 && PyErr_Occurred()) return -1;
  u[j] = x;   /* NaN is refused by the library, with the input and the time */
  return 0;
}

/* values (a mapping by input name: the others keep their value; a sequence of one value per
 * input; a number when there is one input) into u, which holds the values in force; 0 or -1 with an exception. */
static int take_values(ap_sim *sim, PyObject *values, double *u) {
  int nu = ap_sim_input_count(sim);
  if (PyDict_Check(values)) {
    PyObject *key, *val;
    Py_ssize_t pos = 0;
    while (PyDict_Next(values, &pos, &key, &val))
      if (take_named(sim, key, val, u)) return -1;
    return 0;
  }
  if (nu == 1 && PyNumber_Check(values) && !PySequence_Check(values) &&
      !PyArray_Check(values)) {   /* a lone number for a lone input */
    u[0] = PyFloat_AsDouble(values);
    return u[0] == -1.0 && PyErr_Occurred() ? -1 : 0;
  }
  PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(values, NPY_DOUBLE, 1, 1,
                                                      NPY_ARRAY_CARRAY_RO);
  if (!a) return -1;
  int ok = PyArray_DIM(a, 0) == nu;
  if (ok) memcpy(u, PyArray_DATA(a), sizeof(double) * (size_t)nu);
  else PyErr_Format(PyExc_ValueError, "inputs: expected %d values (%s%s) or a dict by name, "
                    "got %zd", nu, ap_sim_input_name(sim, 0), nu > 1 ? ", ..." : "",
                    (Py_ssize_t)PyArray_DIM(a, 0));
  Py_DECREF(a);
  return ok ? 0 : -1;
}

/* ---- the handle --------------------------------------------------------------------------- */

static void ctrl_free(PyObject *capsule) {
  apx_ctrl *c = PyCapsule_GetPointer(capsule, APX_CTRL_CAPSULE);
  if (!c) return;
  ap_scene_out_free(c->out);
  PyMem_Free(c->row);
  Py_XDECREF(c->f), Py_XDECREF(c->simobj), Py_XDECREF(c->keys);
  Py_XDECREF(c->key_q), Py_XDECREF(c->key_v), Py_XDECREF(c->exc);
  PyMem_Free(c);
}

static PyObject *make_keys(const ap_scene *sc, int n, int k, int nc) {
  const ap_model *m = ap_scene_model(sc);
  PyObject *keys = PyTuple_New(n + k + nc);
  for (int i = 0; keys && i < n + k + nc; i++) {
    const char *name = i < n ? ap_model_coord_name(m, i) : i < n + k ? ap_model_speed_name(m, i - n)
                                                                     : ap_scene_output_name(sc, i - n - k);
    PyObject *s = PyUnicode_InternFromString(name ? name : "?");
    if (!s) return Py_DECREF(keys), NULL;
    PyTuple_SET_ITEM(keys, i, s);
  }
  return keys;
}

static apx_ctrl *ctrl_new(PyObject *simobj, ap_sim *sim, const ap_scene *sc, PyObject *f) {
  apx_ctrl *c = PyMem_Calloc(1, sizeof *c);
  if (!c) return (apx_ctrl *)PyErr_NoMemory();
  const ap_model *m = ap_scene_model(sc);
  c->n = ap_model_n(m), c->k = ap_model_k(m), c->nc = ap_scene_output_count(sc);
  c->f = Py_NewRef(f), c->simobj = Py_NewRef(simobj), c->sim = sim;
  c->row = PyMem_Calloc((size_t)c->nc + 1, sizeof *c->row);
  c->keys = make_keys(sc, c->n, c->k, c->nc);
  c->key_q = PyUnicode_InternFromString("q"), c->key_v = PyUnicode_InternFromString("v");
  if (c->row && c->keys && c->key_q && c->key_v && ap_scene_out_create(sc, &c->out) == AP_OK)
    return c;
  PyObject *tmp = PyCapsule_New(c, APX_CTRL_CAPSULE, NULL);   /* to free c in one place */
  if (tmp) ctrl_free(tmp), Py_DECREF(tmp);
  if (!PyErr_Occurred()) PyErr_NoMemory();
  return NULL;
}

/* The measured state: every coordinate, speed and output column by name, q and v. */
static PyObject *make_state(apx_ctrl *c, const double *q, const double *v) {
  int rc = ap_scene_out_row(c->out, c->sim, c->row);
  if (rc != AP_OK) return apx_raise(rc, ap_sim_message(c->sim));
  PyObject *d = PyDict_New();
  for (int i = 0; d && i < c->n + c->k + c->nc; i++) {
    double x = i < c->n ? q[i] : i < c->n + c->k ? v[i - c->n] : c->row[i - c->n - c->k];
    PyObject *val = PyFloat_FromDouble(x);
    if (!val || PyDict_SetItem(d, PyTuple_GET_ITEM(c->keys, i), val)) Py_CLEAR(d);
    Py_XDECREF(val);
  }
  PyObject *qa = d ? apx_vector(q, c->n) : NULL, *va = qa ? apx_vector(v, c->k) : NULL;
  if (!va || PyDict_SetItem(d, c->key_q, qa) || PyDict_SetItem(d, c->key_v, va)) Py_CLEAR(d);
  Py_XDECREF(qa), Py_XDECREF(va);
  return d;
}

/* Keep the exception being raised (normalized, with its traceback) in the handle. */
static void keep_exception(apx_ctrl *c) {
  PyObject *type, *value, *tb;
  PyErr_Fetch(&type, &value, &tb);
  PyErr_NormalizeException(&type, &value, &tb);
  if (value && tb) PyException_SetTraceback(value, tb);
  Py_XSETREF(c->exc, value);
  Py_XDECREF(type), Py_XDECREF(tb);
}

/* ap_sim_controller_fn: called without the GIL, from inside ap_sim_advance. */
static int trampoline(double t, const double *q, const double *v, double *u, void *user) {
  apx_ctrl *c = user;
  PyGILState_STATE g = PyGILState_Ensure();
  PyObject *state = make_state(c, q, v), *res = NULL;
  if (state) res = PyObject_CallFunction(c->f, "dO", t, state);
  int rc = res && take_values(c->sim, res, u) == 0 ? 0 : -1;
  if (rc != 0) keep_exception(c);
  Py_XDECREF(state), Py_XDECREF(res);
  PyGILState_Release(g);
  return rc;
}

/* ---- module functions --------------------------------------------------------------------- */

PyObject *apx_set_controller(PyObject *self, PyObject *args) {
  (void)self;
  PyObject *simobj, *f;
  double period = 0.0;
  if (!PyArg_ParseTuple(args, "OOd", &simobj, &f, &period)) return NULL;
  const ap_scene *sc = NULL;
  ap_sim *sim = apx_sim_handle(simobj, &sc, 1);
  if (!sim) return NULL;
  if (f == Py_None) {
    ap_sim_set_controller(sim, NULL, 0.0, NULL);
    Py_RETURN_NONE;
  }
  if (!PyCallable_Check(f)) return PyErr_SetString(PyExc_TypeError, "controller must be "
                                                   "callable: f(t, state) -> inputs"), NULL;
  if (ensure_inputs(sim, sc)) return NULL;
  apx_ctrl *c = ctrl_new(simobj, sim, sc, f);
  PyObject *capsule = c ? PyCapsule_New(c, APX_CTRL_CAPSULE, ctrl_free) : NULL;
  if (!capsule) return NULL;
  int rc = ap_sim_set_controller(sim, trampoline, period, c);
  if (rc == AP_OK) return capsule;
  Py_DECREF(capsule);
  return apx_raise(rc, ap_sim_message(sim));
}

PyObject *apx_controller_error(PyObject *self, PyObject *capsule) {
  (void)self;
  apx_ctrl *c = PyCapsule_GetPointer(capsule, APX_CTRL_CAPSULE);
  if (!c) return NULL;
  PyObject *e = c->exc ? c->exc : Py_None;
  c->exc = NULL;
  return e == Py_None ? Py_NewRef(e) : e;
}

PyObject *apx_set_inputs(PyObject *self, PyObject *args) {
  (void)self;
  PyObject *simobj, *values;
  if (!PyArg_ParseTuple(args, "OO", &simobj, &values)) return NULL;
  const ap_scene *sc = NULL;
  ap_sim *sim = apx_sim_handle(simobj, &sc, 1);
  if (!sim || ensure_inputs(sim, sc)) return NULL;
  int nu = ap_sim_input_count(sim);
  double *u = PyMem_Calloc((size_t)nu, sizeof *u);
  if (!u) return PyErr_NoMemory();
  memcpy(u, ap_sim_inputs(sim), sizeof(double) * (size_t)nu);
  int bad = take_values(sim, values, u), rc = bad ? AP_OK : ap_sim_set_inputs(sim, u);
  PyMem_Free(u);
  if (bad) return NULL;
  if (rc != AP_OK) return apx_raise(rc, ap_sim_message(sim));
  Py_RETURN_NONE;
}

PyObject *apx_get_inputs(PyObject *self, PyObject *simobj) {
  (void)self;
  const ap_scene *sc = NULL;
  ap_sim *sim = apx_sim_handle(simobj, &sc, 1);
  if (!sim || ensure_inputs(sim, sc)) return NULL;
  PyObject *d = PyDict_New();
  for (int j = 0; d && j < ap_sim_input_count(sim); j++) {
    PyObject *x = PyFloat_FromDouble(ap_sim_inputs(sim)[j]);
    if (!x || PyDict_SetItemString(d, ap_sim_input_name(sim, j), x)) Py_CLEAR(d);
    Py_XDECREF(x);
  }
  return d;
}
