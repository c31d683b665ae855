/* The complex-step build of con_user.c (model/con_kind.h): refuses by name. */
#define AP_SC_COMPLEX 1
#include "model/con_user.c"
