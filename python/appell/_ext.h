/* appell._appell: the CPython extension (C, NumPy C API) behind the appell package.
 *
 *   _module.c   the module, the exceptions (Error, SceneError) and shared helpers
 *   _model.c    Model: a loaded scene (ap_scene) and what it tells about itself
 *   _sim.c      Simulation: one ap_sim with its own output evaluator (ap_scene_out)
 *   _batch.c    run_plan: a slice of a sweep plan on the batch API's thread pool
 *   _lin.c      linearize: operating points, A and B, eigenvalues, speed sweeps
 *   _io.c       write_file: files written by the rules of appell run --out (outfile.h)
 *   _ctrl.c     inputs and controllers in the loop (control.h)
 *   _accuracy.c _error_estimate, _pick: accuracy on demand (include/appell/accuracy.h)
 *
 * Only the public C API (<appell/appell.h>) is used. Integration and batches run with the
 * GIL released; a Model is only read by Simulations and may be shared by Python threads. */
#ifndef APPELL_PY_EXT_H
#define APPELL_PY_EXT_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL appell_ARRAY_API
#ifndef APX_MAIN_FILE
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include <appell/appell.h>

/* A loaded scene: the text, name and overrides it came from (sweeps reload it elsewhere). */
typedef struct apx_model {
  PyObject_HEAD
  ap_scene *sc;
  PyObject *text;          /* bytes */
  PyObject *name;          /* str: the file name in messages */
  PyObject *sets;          /* tuple of str "path=value" */
} apx_model;

extern PyTypeObject apx_model_type;
extern PyTypeObject apx_sim_type;
extern PyObject *apx_error;        /* appell.Error */
extern PyObject *apx_scene_error;  /* appell.SceneError (bad input with file:line:column) */

/* Raise Error (or SceneError when msg starts with FILE:LINE:COLUMN:) with .status, .reason
 * (ap_strerror) and .message; returns NULL. */
PyObject *apx_raise(int status, const char *msg);
/* The same for loading a scene: AP_ERR_ARG is always a SceneError (its location None when
 * the message has none, e.g. a bad --set path). */
PyObject *apx_raise_input(int status, const char *msg);
/* The message of a run of scene sc that failed (status rc) advancing to tout (NaN: unknown):
 * the scene expression at fault first when there is one (FILE:LINE:COLUMN: ..., so that
 * apx_raise makes it a SceneError), then "the simulation failed at t = ...: reason: detail". */
void apx_run_message(const ap_scene *sc, const ap_sim *sim, int rc, double tout, char *msg,
                     size_t len);
/* A tuple of str as a NULL-terminated array of UTF-8 pointers into the tuple's items (valid
 * while the tuple lives); NULL with an exception set on failure. */
const char **apx_strings(PyObject *tuple, Py_ssize_t *n);
/* A tuple of str from any iterable of str (None: empty tuple). */
PyObject *apx_str_tuple(PyObject *obj, const char *what);
/* A new 1-D float64 array copied from x (n). */
PyObject *apx_vector(const double *x, int n);
/* The simulation's event records as a list of dicts (_events.c). */
PyObject *apx_events(const ap_sim *sim);

PyObject *apx_load(PyObject *self, PyObject *args, PyObject *kw);
PyObject *apx_loads(PyObject *self, PyObject *args, PyObject *kw);
PyObject *apx_run_plan(PyObject *self, PyObject *args, PyObject *kw);
PyObject *apx_plan_info(PyObject *self, PyObject *args, PyObject *kw);
PyObject *apx_constant(PyObject *self, PyObject *args);
PyObject *apx_linearize(PyObject *self, PyObject *args, PyObject *kw);
PyObject *apx_write_file(PyObject *self, PyObject *args, PyObject *kw);
/* Inputs and controllers (_ctrl.c): the simulation of a Simulation object and its scene (NULL
 * with TypeError for another object, or RuntimeError when idle is asked and another thread
 * runs it); the module functions. */
ap_sim *apx_sim_handle(PyObject *obj, const ap_scene **sc, int idle);
PyObject *apx_set_controller(PyObject *self, PyObject *args);
PyObject *apx_controller_error(PyObject *self, PyObject *capsule);
PyObject *apx_set_inputs(PyObject *self, PyObject *args);
PyObject *apx_get_inputs(PyObject *self, PyObject *sim);
PyObject *apx_error_estimate(PyObject *self, PyObject *args);   /* _accuracy.c */
PyObject *apx_pick(PyObject *self, PyObject *args);
PyObject *apx_urdf(PyObject *self, PyObject *args, PyObject *kw);

#endif
