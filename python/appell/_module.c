/* appell._appell: module definition, exceptions and helpers shared by the extension's files
 * (_ext.h lists them). Exceptions: Error(Exception) for every failure the library reports,
 * with .status (the AP_ERR_* code), .reason (its text) and .message; SceneError(Error,
 * ValueError) for bad input located in a scene, with .filename, .line and .column too. */
#define APX_MAIN_FILE
#include "_ext.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

PyObject *apx_error = NULL;
PyObject *apx_scene_error = NULL;

/* "FILE:LINE:COLUMN: ..." -> the three parts; 0 when msg has no such prefix. A URDF file's
 * "FILE.urdf:LINE: ..." gives column 0 (None). */
static int location(const char *msg, PyObject **file, long *line, long *col) {
  for (const char *c = strchr(msg, ':'); c; c = strchr(c + 1, ':')) {
    char *end1 = NULL, *end2 = NULL;
    long l = strtol(c + 1, &end1, 10);
    if (end1 == c + 1 || *end1 != ':') continue;
    if (end1[1] == ' ' && l >= 1 && c - msg >= 5 && strncmp(c - 5, ".urdf", 5) == 0) {
      *file = PyUnicode_DecodeUTF8(msg, c - msg, "replace");
      *line = l, *col = 0;
      return *file != NULL;
    }
    long k = strtol(end1 + 1, &end2, 10);
    if (end2 == end1 + 1 || *end2 != ':' || l < 1 || k < 1) continue;
    *file = PyUnicode_DecodeUTF8(msg, c - msg, "replace");
    *line = l, *col = k;
    return *file != NULL;
  }
  return 0;
}

static int set_attrs(PyObject *exc, int status, const char *msg) {
  PyObject *st = PyLong_FromLong(status), *reason = PyUnicode_FromString(ap_strerror(status));
  PyObject *text = PyUnicode_DecodeUTF8(msg, (Py_ssize_t)strlen(msg), "replace");
  int rc = st && reason && text && !PyObject_SetAttrString(exc, "status", st) &&
           !PyObject_SetAttrString(exc, "reason", reason) &&
           !PyObject_SetAttrString(exc, "message", text) ? 0 : -1;
  Py_XDECREF(st);
  Py_XDECREF(reason);
  Py_XDECREF(text);
  return rc;
}

/* Raise cls (SceneError: with .filename, .line, .column, None when msg has no location). */
static PyObject *raise_as(PyObject *cls, int status, const char *msg) {
  PyObject *file = NULL;
  long line = 0, col = 0;
  int located = location(msg, &file, &line, &col);
  PyObject *exc = PyObject_CallFunction(cls, "s", msg);
  if (exc && set_attrs(exc, status, msg) != 0) Py_CLEAR(exc);
  if (exc && cls == apx_scene_error) {
    PyObject *l = located ? PyLong_FromLong(line) : Py_NewRef(Py_None);
    PyObject *c = located && col > 0 ? PyLong_FromLong(col) : Py_NewRef(Py_None);
    if (!l || !c || PyObject_SetAttrString(exc, "filename", located ? file : Py_None) ||
        PyObject_SetAttrString(exc, "line", l) || PyObject_SetAttrString(exc, "column", c))
      Py_CLEAR(exc);
    Py_XDECREF(l);
    Py_XDECREF(c);
  }
  Py_XDECREF(file);
  if (exc) {
    PyErr_SetObject(cls, exc);
    Py_DECREF(exc);
  }
  return NULL;
}

PyObject *apx_raise(int status, const char *msg) {
  if (!msg || !msg[0]) msg = ap_strerror(status);
  PyObject *file = NULL;
  long line = 0, col = 0;
  int located = location(msg, &file, &line, &col);
  Py_XDECREF(file);
  return raise_as(located ? apx_scene_error : apx_error, status, msg);
}

void apx_run_message(const ap_scene *sc, const ap_sim *sim, int rc, double tout, char *msg,
                     size_t len) {
  char where[1024] = "";
  if (ap_scene_locate_failure(sc, sim, tout, where, sizeof where) == AP_OK) where[0] = '\0';
  snprintf(msg, len, "%s%sthe simulation failed at t = %.10g: %s: %s", where,
           where[0] ? "; " : "", ap_sim_time(sim), ap_strerror(rc), ap_sim_message(sim));
}

PyObject *apx_raise_input(int status, const char *msg) {
  if (!msg || !msg[0]) msg = ap_strerror(status);
  return status == AP_ERR_ARG ? raise_as(apx_scene_error, status, msg) : apx_raise(status, msg);
}

PyObject *apx_str_tuple(PyObject *obj, const char *what) {
  if (!obj || obj == Py_None) return PyTuple_New(0);
  if (PyUnicode_Check(obj))
    return PyErr_Format(PyExc_TypeError, "%s: expected a sequence of str, got a str", what);
  PyObject *t = PySequence_Tuple(obj);
  for (Py_ssize_t i = 0; t && i < PyTuple_GET_SIZE(t); i++)
    if (!PyUnicode_Check(PyTuple_GET_ITEM(t, i))) {
      PyErr_Format(PyExc_TypeError, "%s: item %zd is not a str", what, i);
      Py_CLEAR(t);
    }
  return t;
}

const char **apx_strings(PyObject *tuple, Py_ssize_t *n) {
  *n = PyTuple_GET_SIZE(tuple);
  const char **s = PyMem_Calloc((size_t)*n + 1, sizeof *s);
  if (!s) return (const char **)PyErr_NoMemory();
  for (Py_ssize_t i = 0; i < *n; i++) {
    Py_ssize_t len = 0;
    if (!(s[i] = PyUnicode_AsUTF8AndSize(PyTuple_GET_ITEM(tuple, i), &len))) {
      PyMem_Free(s);
      return NULL;
    }
    if ((size_t)len != strlen(s[i])) {   /* C would read only up to the NUL */
      PyErr_Format(PyExc_ValueError, "a NUL character inside %R (item %zd)",
                   PyTuple_GET_ITEM(tuple, i), i);
      PyMem_Free(s);
      return NULL;
    }
  }
  return s;
}

PyObject *apx_vector(const double *x, int n) {
  npy_intp dim = n;
  PyObject *a = PyArray_SimpleNew(1, &dim, NPY_DOUBLE);
  if (a && n) memcpy(PyArray_DATA((PyArrayObject *)a), x, sizeof(double) * (size_t)n);
  return a;
}

PyObject *apx_constant(PyObject *self, PyObject *args) {
  (void)self;
  const char *text;
  if (!PyArg_ParseTuple(args, "s", &text)) return NULL;
  double x = 0.0;
  char msg[512];
  int rc = ap_scene_constant(text, &x, msg, sizeof msg);
  return rc == AP_OK ? PyFloat_FromDouble(x) : apx_raise(rc, msg);
}

static PyObject *methods_list(PyObject *self, PyObject *noargs) {
  (void)self, (void)noargs;
  PyObject *out = PyList_New(0);
  for (int i = 0; out && i < ap_method_count(); i++) {
    ap_method_info info;
    if (ap_method_get(i, &info) != AP_OK) continue;
    PyObject *d = Py_BuildValue("{s:s,s:s,s:i,s:O}", "name", info.name, "summary", info.summary,
                                "order", info.order, "adaptive",
                                info.adaptive ? Py_True : Py_False);
    if (!d || PyList_Append(out, d)) Py_CLEAR(out);
    Py_XDECREF(d);
  }
  return out;
}

static PyMethodDef module_methods[] = {
    {"load", (PyCFunction)(void (*)(void))apx_load, METH_VARARGS | METH_KEYWORDS,
     "load(path, sets=()) -> Model: read, validate and compile a scene file"},
    {"loads", (PyCFunction)(void (*)(void))apx_loads, METH_VARARGS | METH_KEYWORDS,
     "loads(text, name='scene', sets=()) -> Model: the same from text"},
    {"run_plan", (PyCFunction)(void (*)(void))apx_run_plan, METH_VARARGS | METH_KEYWORDS,
     "run a slice of a sweep plan on a thread pool (appell.sweep uses it)"},
    {"plan_info", (PyCFunction)(void (*)(void))apx_plan_info, METH_VARARGS | METH_KEYWORDS,
     "plan_info(grids, randoms, samples, seed) -> (runs, paths)"},
    {"constant", apx_constant, METH_VARARGS,
     "constant(text) -> float: a constant expression of the scene grammar (70*deg)"},
    {"methods", methods_list, METH_NOARGS, "the steppers on offer (name, summary, order)"},
    {"linearize", (PyCFunction)(void (*)(void))apx_linearize, METH_VARARGS | METH_KEYWORDS,
     "linearize(model, speed, about, free, inputs, states, keep_cyclic, sweep, ptol) -> dict "
     "(appell.linearize wraps it)"},
    {"write_file", (PyCFunction)(void (*)(void))apx_write_file, METH_VARARGS | METH_KEYWORDS,
     "write_file(path, data, keep=()): write bytes by appell run --out's rules (_io.c)"},
    {"_set_controller", apx_set_controller, METH_VARARGS,
     "_set_controller(sim, f, period) -> handle or None (Simulation.run(controller=) uses it)"},
    {"_controller_error", apx_controller_error, METH_O,
     "_controller_error(handle) -> the exception the controller raised, or None"},
    {"_set_inputs", apx_set_inputs, METH_VARARGS, "_set_inputs(sim, values): dict or array"},
    {"_inputs", apx_get_inputs, METH_O, "_inputs(sim) -> dict of the input values now"},
    {"_error_estimate", apx_error_estimate, METH_VARARGS,
     "_error_estimate(model, settings, t0, q0, v0, table) -> dict (_accuracy.c)"},
    {"_pick", apx_pick, METH_VARARGS,
     "_pick(model, accuracy, settings, t0, q0, v0, t_end, dt) -> dict (_accuracy.c)"},
    {"urdf", (PyCFunction)(void (*)(void))apx_urdf, METH_VARARGS | METH_KEYWORDS,
     "urdf(path, wheels=(), torus=False) -> str: a URDF file as scene text (_urdf.c)"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_appell",
    "The C extension of the appell package (use the package, not this module).", -1,
    module_methods, NULL, NULL, NULL, NULL};

static int add_exceptions(PyObject *m) {
  apx_error = PyErr_NewExceptionWithDoc(
      "appell.Error",
      "A failure reported by the Appell library: .status (the library's code), .reason "
      "(its text) and .message (what failed, where, and the number).",
      NULL, NULL);
  PyObject *bases = apx_error ? PyTuple_Pack(2, apx_error, PyExc_ValueError) : NULL;
  apx_scene_error = bases ? PyErr_NewExceptionWithDoc(
                                "appell.SceneError",
                                "Bad input in a scene: also .filename, .line and .column.",
                                bases, NULL)
                          : NULL;
  Py_XDECREF(bases);
  if (!apx_scene_error) return -1;
  Py_INCREF(apx_error);
  Py_INCREF(apx_scene_error);
  return PyModule_AddObject(m, "Error", apx_error) ||
         PyModule_AddObject(m, "SceneError", apx_scene_error);
}

PyMODINIT_FUNC PyInit__appell(void) {
  import_array();
  if (PyType_Ready(&apx_model_type) < 0 || PyType_Ready(&apx_sim_type) < 0) return NULL;
  PyObject *m = PyModule_Create(&module_def);
  if (!m) return NULL;
  Py_INCREF(&apx_model_type);
  Py_INCREF(&apx_sim_type);
  if (add_exceptions(m) || PyModule_AddObject(m, "Model", (PyObject *)&apx_model_type) ||
      PyModule_AddObject(m, "Simulation", (PyObject *)&apx_sim_type) ||
      PyModule_AddStringConstant(m, "version", AP_VERSION_STRING) ||
      PyModule_AddIntConstant(m, "NOT_RUN", AP_BATCH_NOT_RUN)) {
    Py_DECREF(m);
    return NULL;
  }
  return m;
}
