/* path_ems: emitter sampling at every non-delta vertex; emission found by the path itself only from the
   camera ray and after delta bounces. */
#define PATH_USE_EMS
#include "path.h"
