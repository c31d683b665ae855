/* appell._appell.write_file: every file the Python package writes goes through the library's
 * output-file rules (include/appell/outfile.h, the same code as `appell run --out`): a
 * regular file is written as a temporary file beside it and renamed over it only when
 * complete; a FIFO or a device is written in place, never replaced; a symbolic link is
 * followed; a directory, a missing directory and the files in `keep` (the scene) are refused;
 * on any failure nothing is left behind. The write runs with the GIL released (opening a FIFO
 * waits for its reader). A failure raises OSError with the errno value, so Python picks the
 * subclass (IsADirectoryError, FileNotFoundError, FileExistsError for a kept file, ...). */
#include "_ext.h"

/* The paths of an iterable of path-like objects as bytes (os.fsencode), in a new list. */
static PyObject *encoded_paths(PyObject *keep) {
  PyObject *out = PyList_New(0), *it = keep == Py_None ? NULL : PyObject_GetIter(keep);
  if (!out || (keep != Py_None && !it)) return Py_XDECREF(out), Py_XDECREF(it), NULL;
  for (PyObject *item; it && (item = PyIter_Next(it));) {
    PyObject *b = NULL;
    int ok = PyUnicode_FSConverter(item, &b) && PyList_Append(out, b) == 0;
    Py_DECREF(item);
    Py_XDECREF(b);
    if (!ok) return Py_DECREF(out), Py_DECREF(it), NULL;
  }
  Py_XDECREF(it);
  return PyErr_Occurred() ? (Py_DECREF(out), NULL) : out;
}

PyObject *apx_write_file(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"path", "data", "keep", NULL};
  PyObject *path = NULL, *keep = Py_None, *result = NULL;
  Py_buffer data = {0};
  if (!PyArg_ParseTupleAndKeywords(args, kw, "O&y*|O", kwlist, PyUnicode_FSConverter, &path,
                                   &data, &keep))
    return NULL;
  PyObject *kept = encoded_paths(keep);
  Py_ssize_t nkeep = kept ? PyList_GET_SIZE(kept) : 0;
  const char **names = kept ? PyMem_Calloc((size_t)nkeep + 1, sizeof *names) : NULL;
  if (kept && !names) PyErr_NoMemory();
  for (Py_ssize_t i = 0; names && i < nkeep; i++)
    names[i] = PyBytes_AS_STRING(PyList_GET_ITEM(kept, i));
  if (names && !PyErr_Occurred()) {
    char msg[2 * AP_OUT_PATH_MAX + 300];
    int err = 0, rc;
    const char *target = PyBytes_AS_STRING(path);
    Py_BEGIN_ALLOW_THREADS
    rc = ap_out_write_file(target, data.buf, (size_t)data.len, names, (int)nkeep, &err, msg,
                           sizeof msg);
    Py_END_ALLOW_THREADS
    if (rc == AP_OK) {
      result = Py_NewRef(Py_None);
    } else {
      PyObject *name = PyUnicode_DecodeFSDefault(target);
      PyObject *exc = name ? PyObject_CallFunction(PyExc_OSError, "isO", err ? err : 5, msg,
                                                   name)
                           : NULL;
      if (exc) PyErr_SetObject((PyObject *)Py_TYPE(exc), exc);
      Py_XDECREF(exc);
      Py_XDECREF(name);
    }
  }
  PyMem_Free(names);
  Py_XDECREF(kept);
  Py_DECREF(path);
  PyBuffer_Release(&data);
  return result;
}
