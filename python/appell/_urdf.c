/* appell._appell.urdf: a URDF robot description as scene text (ap_urdf_to_scene,
 * lib/scene/urdf.c); appell.load of a .urdf file loads that text. Bad input raises
 * SceneError located at the URDF's line (.column None). */
#include "_ext.h"

#include <string.h>

PyObject *apx_urdf(PyObject *self, PyObject *args, PyObject *kw) {
  (void)self;
  static char *kwlist[] = {"path", "wheels", "torus", NULL};
  const char *path = NULL;
  PyObject *wheels_in = NULL;
  int torus = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "s|Op", kwlist, &path, &wheels_in, &torus))
    return NULL;
  PyObject *wheels = apx_str_tuple(wheels_in, "wheels");
  if (!wheels) return NULL;
  Py_ssize_t n = PyTuple_GET_SIZE(wheels);
  const char **names = PyMem_Calloc((size_t)n + 1, sizeof *names);
  if (!names) return Py_DECREF(wheels), PyErr_NoMemory();
  for (Py_ssize_t i = 0; i < n; i++)
    if (!(names[i] = PyUnicode_AsUTF8(PyTuple_GET_ITEM(wheels, i)))) break;
  PyObject *out = NULL;
  if (!PyErr_Occurred()) {
    ap_urdf_def def = ap_urdf_def_default();
    def.wheels = names;
    def.nwheels = (int)n;
    def.wheel_shape = torus ? AP_URDF_WHEEL_TORUS : AP_URDF_WHEEL_DISK;
    char *yaml = NULL, msg[1024];
    size_t len = 0;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = ap_urdf_to_scene(path, &def, &yaml, &len, msg, sizeof msg);
    Py_END_ALLOW_THREADS
    out = rc == AP_OK ? PyUnicode_DecodeUTF8(yaml, (Py_ssize_t)len, "strict")
                      : apx_raise_input(rc, msg);
    ap_scene_text_free(yaml);
  }
  PyMem_Free(names);
  Py_DECREF(wheels);
  return out;
}
