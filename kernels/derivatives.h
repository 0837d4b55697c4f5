/* Whether the program carries the surface's partial derivatives dp/du, dp/dv from a hit to the BSDF query
   (Intersection.dpdu/dpdv, BsdfQuery.dpdu/dpdv/ng/dpdu_world): only a BSDF that reads them needs them (bumpmap, the
   slope of a height texture over the surface), so a program specialised to a scene without one does not pay for
   them. A build without a plugin set (unit-test kernels) holds every plugin, hence them too. */
#ifndef CLRENDER_DERIVATIVES_H
#define CLRENDER_DERIVATIVES_H
#if !defined(CLR_PLUGIN_SET) || defined(CLR_USE_ALL_PLUGINS) || defined(CLR_USE_BSDF_BUMPMAP)
#define CLR_SURFACE_DERIVATIVES 1
#endif
#endif
