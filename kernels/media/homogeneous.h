/* homogeneous: constant extinction sigma_t (scale already applied) and single-scattering albedo. Row:
   p.homogeneous.sigma_t, .albedo (xyz), .albedo_volume (a row of `volumes`, or NONE: the albedo is .albedo). Free
   flights are closed forms (kernels/integrators/media.h), so it has no majorant or clip. */
#ifndef CLRENDER_MEDIA_HOMOGENEOUS_H
#define CLRENDER_MEDIA_HOMOGENEOUS_H
#include "math.h"
#include "gen/volume_dispatch.h"

INLINE vec3 homogeneous_sigma_t(const SceneData* sd, __global const Medium* m, vec3 p) {
    return vrow(m->p.homogeneous.sigma_t);
}
INLINE vec3 homogeneous_albedo(const SceneData* sd, __global const Medium* m, vec3 p) {
    uint v = m->p.homogeneous.albedo_volume;
    return v == NONE ? vrow(m->p.homogeneous.albedo) : volume_eval(sd, sd->volumes + v, p);
}
#endif
