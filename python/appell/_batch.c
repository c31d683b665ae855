/* appell._appell.run_plan: runs first .. first + count - 1 of a sweep plan on the batch API's
 * thread pool (include/appell/batch.h), with the GIL released, and returns the table as NumPy
 * arrays: the parameters (a float column each; a list of str for a parameter with words), the
 * batch's columns, the statuses and the messages. appell.sweep (and each Dask chunk) calls it;
 * the plan is rebuilt from its text specs wherever it runs, and gives the same values there.
 * The progress callback runs in the calling thread with the GIL; an exception in it, or a
 * signal (Ctrl-C), cancels the batch and is raised once the running runs have finished. */
#include "_ext.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static ap_plan *make_plan(PyObject *grids, PyObject *randoms, long samples,
                          unsigned long long seed) {
  ap_plan *p = NULL;
  if (ap_plan_create(&p) != AP_OK) return (ap_plan *)PyErr_NoMemory();
  char msg[1024];
  for (int pass = 0; pass < 2; pass++) {
    PyObject *t = pass ? randoms : grids;
    for (Py_ssize_t i = 0; i < PyTuple_GET_SIZE(t); i++) {
      const char *spec = PyUnicode_AsUTF8(PyTuple_GET_ITEM(t, i));
      int rc = !spec ? AP_ERR_ARG : pass ? ap_plan_add_random(p, spec, msg, sizeof msg)
                                         : ap_plan_add_grid(p, spec, msg, sizeof msg);
      if (rc != AP_OK) {
        if (spec) PyErr_Format(PyExc_ValueError, "%s %s", pass ? "random" : "grid", msg);
        return ap_plan_free(p), NULL;
      }
    }
  }
  if (PyTuple_GET_SIZE(randoms) && (samples < 1 || ap_plan_set_samples(p, samples, seed) != AP_OK)) {
    PyErr_SetString(PyExc_ValueError, "random parameters need samples >= 1 (and fewer than 2^53 runs)");
    return ap_plan_free(p), NULL;
  }
  return p;
}

static PyObject *paths(const ap_plan *p) {
  PyObject *t = PyTuple_New(ap_plan_nparams(p));
  for (int r = 0; t && r < ap_plan_nparams(p); r++) {
    PyObject *s = PyUnicode_FromString(ap_plan_path(p, r));
    if (!s) return Py_DECREF(t), NULL;
    PyTuple_SET_ITEM(t, r, s);
  }
  return t;
}

PyObject *apx_plan_info(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"grids", "randoms", "samples", "seed", NULL};
  PyObject *g = NULL, *r = NULL;
  long samples = 0;
  unsigned long long seed = 1;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O!O!|lK", kwlist, &PyTuple_Type, &g, &PyTuple_Type,
                                   &r, &samples, &seed))
    return NULL;
  ap_plan *p = make_plan(g, r, samples, seed);
  if (!p) return NULL;
  PyObject *out = Py_BuildValue("(lN)", ap_plan_count(p), paths(p));
  ap_plan_free(p);
  return out;
}

/* ---- running ------------------------------------------------------------------------------ */

typedef struct py_progress {
  PyObject *fn;            /* callable(done, total) or None */
  PyObject *type, *value, *tb;   /* the exception that cancelled the batch */
} py_progress;

static int on_progress(long done, long total, void *user) {
  py_progress *pp = user;
  PyGILState_STATE g = PyGILState_Ensure();
  int stop = 0;
  if (pp->fn != Py_None) {
    PyObject *r = PyObject_CallFunction(pp->fn, "ll", done, total);
    Py_XDECREF(r);
  }
  if (!PyErr_Occurred()) PyErr_CheckSignals();
  if (PyErr_Occurred()) {
    if (!pp->type) PyErr_Fetch(&pp->type, &pp->value, &pp->tb);
    else PyErr_Clear();
    stop = 1;
  }
  PyGILState_Release(g);
  return stop;
}

/* The parameters of the runs: float columns (count x np) and, for parameters with words, the
 * texts. */
static PyObject *param_table(const ap_plan *p, long first, long count) {
  int np = ap_plan_nparams(p);
  npy_intp dims[2] = {count, np};
  PyObject *x = PyArray_ZEROS(2, dims, NPY_DOUBLE, 0), *words = PyList_New(np);
  char buf[1024];
  for (int r = 0; x && words && r < np; r++) {
    PyObject *list = NULL;
    double *col = (double *)PyArray_DATA((PyArrayObject *)x) + r;
    for (long i = 0; i < count; i++) {
      ap_plan_value(p, first + i, r, &col[(size_t)i * (size_t)np], buf, sizeof buf);
      if (isnan(col[(size_t)i * (size_t)np]) && !list) list = PyList_New(count);
    }
    for (long i = 0; list && i < count; i++) {
      ap_plan_value(p, first + i, r, NULL, buf, sizeof buf);
      PyObject *s = PyUnicode_FromString(strchr(buf, '=') + 1);
      if (!s) Py_CLEAR(list);
      else PyList_SET_ITEM(list, i, s);
    }
    PyList_SET_ITEM(words, r, list ? list : Py_NewRef(Py_None));
  }
  if (x && words && !PyErr_Occurred()) return Py_BuildValue("(NN)", x, words);
  Py_XDECREF(x);
  Py_XDECREF(words);
  return NULL;
}

static PyObject *messages_list(char **msgs, long count) {
  PyObject *l = PyList_New(count);
  for (long i = 0; l && i < count; i++) {
    PyObject *s = msgs[i] ? PyUnicode_DecodeUTF8(msgs[i], (Py_ssize_t)strlen(msgs[i]), "replace")
                          : Py_NewRef(Py_None);
    if (!s) Py_CLEAR(l);
    else PyList_SET_ITEM(l, i, s);
  }
  return l;
}

static PyObject *batch_columns(const ap_batch *b) {
  PyObject *t = PyTuple_New(ap_batch_ncols(b));
  for (int j = 0; t && j < ap_batch_ncols(b); j++) {
    PyObject *s = PyUnicode_FromString(ap_batch_col_name(b, j));
    if (!s) return Py_DECREF(t), NULL;
    PyTuple_SET_ITEM(t, j, s);
  }
  return t;
}

/* Run the slice; returns the result dict. */
static PyObject *run(ap_batch *b, const ap_plan *p, long first, long count, py_progress *pp) {
  npy_intp dv[2] = {count, ap_batch_ncols(b)}, ds = count;
  PyArrayObject *values = (PyArrayObject *)PyArray_ZEROS(2, dv, NPY_DOUBLE, 0);
  PyArrayObject *status = (PyArrayObject *)PyArray_ZEROS(1, &ds, NPY_INT32, 0);
  char **msgs = PyMem_Calloc((size_t)count + 1, sizeof *msgs);
  char **evs = PyMem_Calloc((size_t)count + 1, sizeof *evs);
  PyObject *out = NULL;
  if (values && status && msgs && evs) {
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = ap_batch_run_plan_events(b, p, first, count, PyArray_DATA(values),
                                  PyArray_DATA(status), msgs, evs);
    Py_END_ALLOW_THREADS
    if (pp->type) PyErr_Restore(pp->type, pp->value, pp->tb);
    else if (rc == AP_BATCH_CANCELLED) PyErr_SetString(PyExc_KeyboardInterrupt, "sweep cancelled");
    else if (rc != AP_OK)   /* when nothing ran (row 0 not run), its message says why */
      apx_raise(rc, count > 0 && ((int *)PyArray_DATA(status))[0] == AP_BATCH_NOT_RUN && msgs[0]
                        ? msgs[0] : "the sweep could not start");
    else {
      PyObject *params = param_table(p, first, count);
      char id[17] = "";
      ap_batch_plan_id(b, p, id, sizeof id);
      out = params ? Py_BuildValue("{s:N,s:N,s:N,s:O,s:O,s:N,s:N,s:l,s:s}", "paths",
                                   paths(p), "params", params, "columns", batch_columns(b),
                                   "values", values, "status", status, "messages",
                                   messages_list(msgs, count), "events",
                                   messages_list(evs, count), "runs", ap_plan_count(p),
                                   "plan", id)
                   : NULL;
    }
    ap_batch_messages_free(count, msgs);
    ap_batch_messages_free(count, evs);
  } else if (!PyErr_Occurred()) {
    PyErr_NoMemory();
  }
  PyMem_Free(msgs);
  PyMem_Free(evs);
  Py_XDECREF(values);
  Py_XDECREF(status);
  return out;
}

static int fill_def(ap_batch_def *def, PyObject *channels, PyObject *times, double **tbuf,
                    const char ***cbuf) {
  Py_ssize_t nc = 0, nt = PySequence_Size(times);
  if (nt < 0 || !(*cbuf = apx_strings(channels, &nc))) return -1;
  *tbuf = PyMem_Calloc((size_t)nt + 1, sizeof **tbuf);
  if (!*tbuf) return PyErr_NoMemory(), -1;
  for (Py_ssize_t i = 0; i < nt; i++) {
    PyObject *o = PySequence_GetItem(times, i);
    (*tbuf)[i] = o ? PyFloat_AsDouble(o) : -1.0;
    Py_XDECREF(o);
    if (PyErr_Occurred()) return -1;
  }
  def->channels = *cbuf, def->nchannels = (int)nc, def->times = *tbuf, def->ntimes = (int)nt;
  return 0;
}

PyObject *apx_run_plan(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"text", "name", "sets", "grids", "randoms", "samples", "seed", "first",
                           "count", "channels", "times", "final_state", "jobs", "progress",
                           "check", NULL};
  Py_buffer text;
  const char *name;
  PyObject *sets, *grids, *randoms, *channels, *times, *progress = Py_None;
  long samples, first, count;
  unsigned long long seed;
  int final_state = 1, jobs = 1, check = 1;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "y*sO!O!O!lKllO!O|piOp", kwlist, &text, &name,
                                   &PyTuple_Type, &sets, &PyTuple_Type, &grids, &PyTuple_Type,
                                   &randoms, &samples, &seed, &first, &count, &PyTuple_Type,
                                   &channels, &times, &final_state, &jobs, &progress, &check))
    return NULL;
  ap_plan *p = make_plan(grids, randoms, samples, seed);
  ap_batch_def def = ap_batch_def_default();
  def.threads = jobs, def.final_state = final_state, def.progress = on_progress;
  py_progress pp = {progress, NULL, NULL, NULL};
  def.user = &pp;
  double *tbuf = NULL;
  const char **cbuf = NULL, **sbuf = NULL;
  Py_ssize_t nsets = 0;
  ap_batch *b = NULL;
  PyObject *out = NULL;
  char msg[1024];
  if (p && !fill_def(&def, channels, times, &tbuf, &cbuf) && (sbuf = apx_strings(sets, &nsets))) {
    int rc = ap_batch_create(text.buf, (size_t)text.len, name, sbuf, (int)nsets, &def, &b, msg,
                             sizeof msg);
    if (rc == AP_OK && check) rc = ap_batch_check_plan(b, p, msg, sizeof msg);
    if (rc != AP_OK) apx_raise_input(rc, msg);
    else if (first < 0 || count < 0 || first + count > ap_plan_count(p))
      PyErr_Format(PyExc_ValueError, "runs %ld..%ld are not in the plan (%ld runs)", first,
                   first + count - 1, ap_plan_count(p));
    else out = run(b, p, first, count, &pp);
  }
  ap_batch_free(b);
  ap_plan_free(p);
  PyMem_Free(tbuf);
  PyMem_Free(cbuf);
  PyMem_Free(sbuf);
  PyBuffer_Release(&text);
  return out;
}
