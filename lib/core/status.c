/* Status codes to text (include/appell/status.h). */
#include "appell/status.h"

const char *ap_strerror(int status) {
  switch (status) {
    case AP_OK: return "success";
    case AP_RECOVERABLE: return "recoverable failure: retry with a smaller step";
    case AP_STOPPED: return "stopped by an event";
    case AP_ERR_ARG: return "invalid argument or definition";
    case AP_ERR_NOMEM: return "out of memory";
    case AP_ERR_CALLBACK: return "a user callback reported failure";
    case AP_ERR_NAN: return "a value became NaN, Inf or too large to integrate";
    case AP_ERR_SINGULAR: return "singular or indefinite matrix";
    case AP_ERR_INCONSISTENT: return "inconsistent constraints";
    case AP_ERR_RANK: return "the constraints leave no free speed, or their rank changed";
    case AP_ERR_SOLVER: return "the integrator failed";
    case AP_ERR_UNSUPPORTED: return "not supported";
    case AP_ERR_INTERNAL: return "internal error";
    case AP_ERR_INTERRUPTED: return "interrupted";
    case AP_ERR_IO: return "input or output failed";
    default: return "unknown status";
  }
}
