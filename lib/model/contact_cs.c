/* The complex-step build of contact.c (model/model.h): wheel contact geometry, rows and gamma
 * on double _Complex. */
#define AP_SC_COMPLEX 1
#include "model/contact.c"
