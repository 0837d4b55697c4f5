/* The BSDF interface of the integrators. bsdf_eval, bsdf_pdf, bsdf_sample and bsdf_albedo are generated from
   the registered BSDF plugins (clrender/device/codegen.py writes gen/bsdf_dispatch.h: one switch over the row's
   type tag per method, calling <prefix>_<method> of kernels/bsdfs/<prefix>.h):
     bsdf_eval    f (without the cosine); 0 for delta BSDFs
     bsdf_pdf     solid-angle density of wo under bsdf_sample; 0 for delta BSDFs
     bsdf_sample  sets q->wo, q->eta, q->measure and returns f cos(theta_o) / pdf (0 when the sample failed)
     bsdf_albedo  the diffuse colour including textures (1 where a plugin defines none)
   Capabilities come from the row's flags (BSDF_DELTA, BSDF_DIFFUSE, BSDF_GLOSSY), which the plugin declares.
   All directions are in the local shading frame; q->wi points back along the path (= -ray.d).
   The query record and MEASURE_* are in bsdfs/common.h. */
#ifndef CLRENDER_BSDF_H
#define CLRENDER_BSDF_H
#include "gen/bsdf_dispatch.h"

/* BSDFs with only delta lobes (every sample has q->measure == MEASURE_DISCRETE) get no emitter sampling. One with
   both (a smooth plastic, a blend of a conductor and a diffuse) is sampled like a smooth BSDF: eval/pdf hold its
   non-delta part only, and a delta sample comes back with MEASURE_DISCRETE (then no MIS, see the integrators). */
INLINE bool bsdf_is_delta(__global const Bsdf* b) {
    return (b->flags & BSDF_DELTA) != 0u && (b->flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0u;
}

#endif
