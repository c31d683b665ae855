/* appell Model: a scene loaded, validated and compiled (ap_scene), with its names, settings
 * and initial state. A Model is only read by the Simulations made from it (each has its own
 * data and output evaluator), so Python threads may share it. It keeps the scene's text, name
 * and overrides so that sweeps can load it again in other threads or processes. */
#include "_ext.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define APX_MAX_SCENE (16L << 20)   /* as ap_scene_read and ap_scene_load_string */

/* Load text (bytes) named name with the overrides sets (tuple of str). */
static PyObject *make_model(PyObject *text, PyObject *name, PyObject *sets) {
  Py_ssize_t nsets = 0;
  const char **s = apx_strings(sets, &nsets);
  const char *nm = PyUnicode_AsUTF8(name);
  if (!s || !nm) return PyMem_Free(s), NULL;
  char msg[1024];
  ap_scene *sc = NULL;
  int rc;
  Py_BEGIN_ALLOW_THREADS   /* the text and the strings stay alive: their owners are held */
  rc = ap_scene_load_string(PyBytes_AS_STRING(text), (size_t)PyBytes_GET_SIZE(text), nm, s,
                            (int)nsets, &sc, msg, sizeof msg);
  Py_END_ALLOW_THREADS
  PyMem_Free(s);
  if (rc != AP_OK) return apx_raise_input(rc, msg);
  apx_model *m = PyObject_New(apx_model, &apx_model_type);
  if (!m) return ap_scene_free(sc), NULL;
  m->sc = sc;
  m->text = Py_NewRef(text), m->name = Py_NewRef(name), m->sets = Py_NewRef(sets);
  return (PyObject *)m;
}

PyObject *apx_loads(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"text", "name", "sets", NULL};
  PyObject *text = NULL, *name = NULL, *sets_in = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O|UO", kwlist, &text, &name, &sets_in)) return NULL;
  if ((PyUnicode_Check(text) && PyUnicode_GET_LENGTH(text) > APX_MAX_SCENE) ||
      (PyBytes_Check(text) && PyBytes_GET_SIZE(text) > APX_MAX_SCENE)) {   /* before encoding */
    const char *nm = name ? PyUnicode_AsUTF8(name) : "scene";
    char msg[1024];
    if (nm) snprintf(msg, sizeof msg, "%s: larger than 16 MiB: not a scene file", nm);
    return nm ? apx_raise_input(AP_ERR_ARG, msg) : NULL;
  }
  PyObject *bytes = PyUnicode_Check(text) ? PyUnicode_AsUTF8String(text)
                    : PyBytes_Check(text) ? Py_NewRef(text)
                                          : PyErr_Format(PyExc_TypeError, "text must be str or bytes");
  PyObject *nm = name ? Py_NewRef(name) : PyUnicode_FromString("scene");
  PyObject *sets = apx_str_tuple(sets_in, "sets");
  PyObject *m = bytes && nm && sets ? make_model(bytes, nm, sets) : NULL;
  Py_XDECREF(bytes);
  Py_XDECREF(nm);
  Py_XDECREF(sets);
  return m;
}

PyObject *apx_load(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"path", "sets", NULL};
  PyObject *path = NULL, *sets_in = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O&|O", kwlist, PyUnicode_FSConverter, &path,
                                   &sets_in))
    return NULL;
  const char *p = PyBytes_AS_STRING(path);
  char *text = NULL, msg[1024];
  size_t len = 0;
  int rc, err;
  Py_BEGIN_ALLOW_THREADS   /* the CLI's reader and limits: 16 MiB, no directory */
  rc = ap_scene_read(p, &text, &len, msg, sizeof msg);
  err = errno;             /* fopen's when the file could not be opened */
  Py_END_ALLOW_THREADS
  if (rc != AP_OK && err) {   /* a missing file raises FileNotFoundError, as open() does */
    errno = err;
    PyErr_SetFromErrnoWithFilenameObject(PyExc_OSError, path);
    return Py_DECREF(path), NULL;
  }
  PyObject *chunks = rc == AP_OK ? PyBytes_FromStringAndSize(text, (Py_ssize_t)len)
                                 : apx_raise_input(rc, msg);
  ap_scene_text_free(text);
  PyObject *name = chunks ? PyUnicode_DecodeFSDefault(p) : NULL;
  PyObject *sets = name ? apx_str_tuple(sets_in, "sets") : NULL;
  PyObject *m = sets ? make_model(chunks, name, sets) : NULL;
  Py_XDECREF(sets);
  Py_XDECREF(name);
  Py_XDECREF(chunks);
  Py_DECREF(path);
  return m;
}

static void model_dealloc(apx_model *m) {
  ap_scene_free(m->sc);
  Py_XDECREF(m->text);
  Py_XDECREF(m->name);
  Py_XDECREF(m->sets);
  PyObject_Free(m);
}

/* ---- names and settings ---------------------------------------------------------------- */

typedef const char *(*name_fn)(const ap_model *, int);

static PyObject *names(const ap_model *mod, int count, name_fn fn) {
  PyObject *t = PyTuple_New(count);
  for (int i = 0; t && i < count; i++) {
    PyObject *s = PyUnicode_FromString(fn(mod, i));
    if (!s) return Py_DECREF(t), NULL;
    PyTuple_SET_ITEM(t, i, s);
  }
  return t;
}

static const ap_model *M(apx_model *m) { return ap_scene_model(m->sc); }

static PyObject *get_coords(apx_model *m, void *c) {
  (void)c;
  return names(M(m), ap_model_n(M(m)), ap_model_coord_name);
}
static PyObject *get_speeds(apx_model *m, void *c) {
  (void)c;
  return names(M(m), ap_model_k(M(m)), ap_model_speed_name);
}
static PyObject *get_rows(apx_model *m, void *c) {
  (void)c;
  return names(M(m), ap_model_b(M(m)), ap_model_constraint_name);
}

static PyObject *get_channels(apx_model *m, void *c) {
  (void)c;
  int nc = ap_scene_output_count(m->sc);
  PyObject *t = PyTuple_New(nc);
  for (int i = 0; t && i < nc; i++) {
    PyObject *s = PyUnicode_FromString(ap_scene_output_name(m->sc, i));
    if (!s) return Py_DECREF(t), NULL;
    PyTuple_SET_ITEM(t, i, s);
  }
  return t;
}

static PyObject *elements(apx_model *m, void *c) {
  ap_scene_section sec = (ap_scene_section)(intptr_t)c;
  int n = ap_scene_count(m->sc, sec);
  PyObject *d = PyDict_New();
  for (int i = 0; d && i < n; i++) {
    PyObject *kind = PyUnicode_FromString(ap_scene_element_kind(m->sc, sec, i));
    if (!kind || PyDict_SetItemString(d, ap_scene_element_name(m->sc, sec, i), kind))
      Py_CLEAR(d);
    Py_XDECREF(kind);
  }
  return d;
}

static PyObject *get_parameters(apx_model *m, void *c) {
  (void)c;
  PyObject *d = PyDict_New();
  for (int i = 0; d && i < ap_scene_parameter_count(m->sc); i++) {
    const char *name = NULL;
    double value = 0.0;
    ap_scene_parameter(m->sc, i, &name, &value);
    PyObject *v = PyFloat_FromDouble(value);
    if (!v || PyDict_SetItemString(d, name, v)) Py_CLEAR(d);
    Py_XDECREF(v);
  }
  return d;
}

static PyObject *get_settings(apx_model *m, void *c) {
  (void)c;
  static const char *const modes[] = {"minimal", "projected", "dae", "plain"};
  ap_scene_run r;
  ap_scene_get_run(m->sc, &r);
  return Py_BuildValue("{s:s,s:s,s:d,s:d,s:d,s:d,s:d,s:d,s:l,s:d,s:d,s:d}", "mode",
                       modes[r.sim.mode % 4], "method", r.sim.method ? r.sim.method : "dopri5",
                       "rtol", r.sim.rtol, "atol", r.sim.atol, "h_fixed", r.sim.h_fixed,
                       "h_init", r.sim.h_init, "h_max", r.sim.h_max, "rank_rtol",
                       r.sim.rank_rtol, "max_steps", r.sim.max_steps, "t0", r.t0, "t_end",
                       r.t_end, "interval", r.interval);
}

static PyObject *get_int(apx_model *m, void *c) {
  const ap_model *mod = M(m);
  int which = (int)(intptr_t)c;
  return PyLong_FromLong(which == 0 ? ap_model_n(mod) : which == 1 ? ap_model_k(mod)
                                                                   : ap_model_b(mod));
}

static PyObject *get_name(apx_model *m, void *c) {
  (void)c;
  return PyUnicode_FromString(ap_scene_name(m->sc));
}

static PyObject *get_conserves(apx_model *m, void *c) {
  (void)c;
  return PyBool_FromLong(ap_scene_conserves_energy(m->sc));
}

static PyObject *get_source(apx_model *m, void *c) {
  (void)c;
  return PyTuple_Pack(3, m->text, m->name, m->sets);
}

static PyObject *initial_state(apx_model *m, PyObject *noargs) {
  (void)noargs;
  int n = ap_model_n(M(m)), k = ap_model_k(M(m));
  double *q = PyMem_Calloc((size_t)(n + k) + 1, sizeof *q);
  if (!q) return PyErr_NoMemory();
  char report[2048], msg[1024];
  int rc = ap_scene_initial_state(m->sc, q, q + n, report, sizeof report, msg, sizeof msg);
  PyObject *out = NULL;
  if (rc != AP_OK) apx_raise_input(rc, msg);
  else out = Py_BuildValue("(NNs)", apx_vector(q, n), apx_vector(q + n, k), report);
  PyMem_Free(q);
  return out;
}

static PyGetSetDef model_getset[] = {
    {"name", (getter)get_name, NULL, "the scene's name", NULL},
    {"n", (getter)get_int, NULL, "number of coordinates q", (void *)0},
    {"k", (getter)get_int, NULL, "number of speeds v", (void *)1},
    {"b", (getter)get_int, NULL, "number of constraint rows", (void *)2},
    {"coordinate_names", (getter)get_coords, NULL, "names of q (disk.x, disk.qw, ...)", NULL},
    {"speed_names", (getter)get_speeds, NULL, "names of v (disk.vx, disk.wz, ...)", NULL},
    {"constraint_names", (getter)get_rows, NULL, "names of the constraint rows", NULL},
    {"channel_names", (getter)get_channels, NULL,
     "the output columns, as in appell run's CSV header (t first)", NULL},
    {"bodies", (getter)elements, NULL, "{name: shape}", (void *)AP_SCENE_BODIES},
    {"joints", (getter)elements, NULL, "{name: kind}", (void *)AP_SCENE_JOINTS},
    {"constraints", (getter)elements, NULL, "{name: kind}", (void *)AP_SCENE_CONSTRAINTS},
    {"effects", (getter)elements, NULL, "{name: kind}", (void *)AP_SCENE_EFFECTS},
    {"parameters", (getter)get_parameters, NULL,
     "{name: value} of the scene's parameters: section, as evaluated (after set=)", NULL},
    {"settings", (getter)get_settings, NULL,
     "simulation and output settings (mode, method, rtol, atol, t0, t_end, interval, ...)", NULL},
    {"conserves_energy", (getter)get_conserves, NULL,
     "True when nothing in the scene adds or removes energy", NULL},
    {"source", (getter)get_source, NULL, "(text, name, overrides) the model was loaded from",
     NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyMethodDef model_methods[] = {
    {"initial_state", (PyCFunction)initial_state, METH_NOARGS,
     "initial_state() -> (q0, v0, report): the scene's initial state made consistent with the "
     "constraints, and a description of every correction"},
    {NULL, NULL, 0, NULL}};

PyTypeObject apx_model_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "appell.Model",
    .tp_basicsize = sizeof(apx_model),
    .tp_dealloc = (destructor)model_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A scene loaded and compiled: appell.load(path) or appell.loads(text).",
    .tp_getset = model_getset,
    .tp_methods = model_methods,
};
