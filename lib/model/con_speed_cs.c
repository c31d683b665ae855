/* The complex-step build of con_speed.c (model/con_kind.h). */
#define AP_SC_COMPLEX 1
#include "model/con_speed.c"
