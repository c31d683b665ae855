/* appell Simulation.events: the events recorded so far (appell/event.h) as a list of dicts
 * {name, t, direction ("rising" / "falling"), action ("stop" / "log" / "switch"), q, v}. */
#include "_ext.h"

PyObject *apx_events(const ap_sim *sim) {
  static const char *const act[] = {"stop", "log", "switch"};
  int n = ap_sim_event_count(sim);
  PyObject *list = PyList_New(n);
  for (int i = 0; list && i < n; i++) {
    ap_event_record r;
    ap_sim_event_get(sim, i, &r);
    PyObject *d = Py_BuildValue("{s:s,s:d,s:s,s:s,s:N,s:N}", "name", r.name, "t", r.t,
                                "direction", r.direction > 0 ? "rising" : "falling", "action",
                                act[r.action % 3], "q", apx_vector(r.q, r.n), "v",
                                apx_vector(r.v, r.k));
    if (!d) return Py_DECREF(list), NULL;
    PyList_SET_ITEM(list, i, d);
  }
  return list;
}
