/* The complex-step build of con_loop.c (model/con_kind.h). */
#define AP_SC_COMPLEX 1
#include "model/con_loop.c"
