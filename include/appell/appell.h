/* Appell: dynamics of mechanical systems with nonholonomic constraints.
 * The umbrella header: include this one. */
#ifndef APPELL_H
#define APPELL_H

#include "appell/export.h"
#include "appell/status.h"
#include "appell/system.h"
#include "appell/sim.h"
#include "appell/event.h"
#include "appell/body.h"
#include "appell/analyze.h"
#include "appell/scene.h"
#include "appell/batch.h"
#include "appell/outfile.h"
#include "appell/control.h"
#include "appell/accuracy.h"
#include "appell/urdf.h"
#include "appell/compiled.h"

#define AP_VERSION_STRING "0.1.0"

#endif
