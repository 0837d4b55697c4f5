/* The megakernel's loop over the path stages (path.h, path_mitsuba.h): trace, vertex, shadow ray, until the path
   ends. kernels/wavefront.cl runs the same stages as kernels of their own; CLR_PATH_STAGES tells it they are here. */
#ifndef CLRENDER_PATH_LOOP_H
#define CLRENDER_PATH_LOOP_H
#define CLR_PATH_STAGES 1

INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    PathState ps;
    path_begin(sd, &ps, ray);
    while (ps.alive) {
        Hit h;
        bool hit = scene_trace(sd, &ps.ray, &h);
        path_vertex(sd, &ps, hit, &h, smp);
#if defined(CLR_MEDIA) && defined(PATH_MITSUBA)
        /* volpath's shadow rays cross media and pass-through surfaces (media.h); Mitsuba's path ignores media */
        if (ps.shadow_pending && sd->info->p.path_mitsuba.volpath != 0u)
            path_shadow_through(&ps, shadow_transmittance(sd, &ps.shadow, ps.shadow_medium, smp));
#endif
        if (ps.shadow_pending) path_shadow_done(&ps, shadow_occluded(sd, &ps.shadow));
    }
    return path_result(sd, &ps);
}

#endif
