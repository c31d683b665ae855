/* Appell: compiled models (docs/compiled.md).
 *
 * A body model's kinematics (joint transforms, Jacobians, world inertias, g; body velocities,
 * bias accelerations, h) can run as C generated for that one model, compiled at load time by
 * the system C compiler (`cc`, or $APPELL_CC) into a shared object cached under
 * $XDG_CACHE_HOME/appell (else ~/.cache/appell) and loaded with dlopen. It computes the same
 * numbers as the interpreted path (the same operations in the same order, constants folded);
 * constraints, effects and the null-space solve stay the library's. Scenes choose it with
 * `simulation.compile`, the command line with `appell run --compile MODE`, the environment with
 * APPELL_COMPILE (the default when a scene does not say). */
#ifndef APPELL_COMPILED_H
#define APPELL_COMPILED_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/system.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ap_compile_mode {
  AP_COMPILE_NEVER = 0,    /* interpreted (the default) */
  AP_COMPILE_AUTO = 1,     /* compiled when the model allows it and a compiler is there */
  AP_COMPILE_ALWAYS = 2    /* the same; what prevents it is reported in the notice */
} ap_compile_mode;

/* Switch body model m to compiled kinematics. Call it before the first evaluation with any data
 * of m, and not while another thread evaluates m. Returns 1 when m now runs compiled, 0 when it
 * stays interpreted (mode NEVER, or a reason written as one line into notice: no compiler, the
 * compiler failed, the tree path, a math-level model), AP_ERR_ARG for a NULL model or a mode out
 * of range. notice (len bytes) may be NULL; it is set to "" when there is nothing to say. */
AP_API int ap_model_compile_native(const ap_model *m, ap_compile_mode mode, char *notice,
                                   size_t len);
/* 1 when m runs compiled kinematics, else 0. */
AP_API int ap_model_is_compiled(const ap_model *m);
/* "never", "auto", "always" -> mode; AP_OK or AP_ERR_ARG. */
AP_API int ap_compile_mode_parse(const char *name, ap_compile_mode *mode);

#ifdef __cplusplus
}
#endif

#endif
