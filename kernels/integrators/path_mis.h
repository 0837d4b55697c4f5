/* path_mis: emitter sampling and BSDF sampling at every vertex, weighted by the balance heuristic (full
   weight for BSDF samples after delta bounces). */
#define PATH_USE_EMS
#define PATH_USE_MATS
#include "path.h"
