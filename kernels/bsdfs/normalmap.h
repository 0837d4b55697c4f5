/* normalmap: the child in the frame of the normal 2 rgb - 1 that the texture gives, relative to the shading frame
   (kernels/bsdfs/perturb.h). Row: p.normalmap = normalmap(_tex) (a colour or a texture), child (offset of the
   child's row), options (PERTURB_FLIP, PERTURB_SHADOW). Included once per nesting level (see twosided.h). */
#ifndef CLRENDER_BSDFS_NORMALMAP_H
#define CLRENDER_BSDFS_NORMALMAP_H
#include "perturb.h"
INLINE Frame normalmap_frame(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 c = param_color(q, b->p.normalmap.normalmap, b->p.normalmap.normalmap_tex);
    return perturbed_frame(vsub(vscale(c, 2.0f), v3s(1.0f)), q->wi, v3(1.0f, 0.0f, 0.0f), b->p.normalmap.options);
}
#endif

PERTURB_WRAPPER(normalmap)
