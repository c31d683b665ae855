/* The complex-step build of con_knife.c (model/con_kind.h). */
#define AP_SC_COMPLEX 1
#include "model/con_knife.c"
