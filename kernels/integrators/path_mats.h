/* path_mats: follow BSDF samples; count emission wherever a path finds it. */
#define PATH_USE_MATS
#include "path.h"
