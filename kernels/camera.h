/* Nori's perspective camera (as its perspective.cpp computes it): looks down +z in camera space, horizontal
   field of view, pixel (0,0) at the top left, camera +x towards the image's right and +y up. Nori's lookat
   puts camera +x on the viewer's left, so Nori scenes put <scale value="-1,1,1"/> before <lookat> to get an
   unmirrored image; we honour whatever the scene says, literally. */
#ifndef CLRENDER_CAMERA_H
#define CLRENDER_CAMERA_H
#include "math.h"
#include "warp.h"

typedef struct { vec3 o; vec3 d; float tmin; float tmax; } Ray;

/* (sx, sy): position in the image in pixels (0..width, 0..height), which is the window at (crop_x, crop_y) of a
   film_width x film_height film; lens: a uniform 2D sample for the thin lens (unused when lens_radius is 0). */
INLINE Ray camera_ray_lens(__global const Camera* cam, float sx, float sy, float2 lens) {
    float nx = (sx + cam->crop_x) / cam->film_width, ny = (sy + cam->crop_y) / cam->film_height;
    if (cam->ortho != 0u) {
        /* Mitsuba's orthographic sensor: from the point (2nx - 1, (1 - 2ny) height/width, near) of camera space
           (its x and y axes scaled by to_world: the visible area), along z, for far - near */
        vec3 X = vrow(cam->to_world[0]), Y = vrow(cam->to_world[1]), Z = vrow(cam->to_world[2]);
        Ray r;
        vec3 o = vmad(X, 2.0f * nx - 1.0f, vrow(cam->to_world[3]));
        o = vmad(Y, (1.0f - 2.0f * ny) * cam->inv_aspect, o);
        r.o = vmad(Z, cam->near_clip, o);
        r.d = vscale(Z, 1.0f / len3(Z));
        r.tmin = 0.0f;
        r.tmax = cam->far_clip - cam->near_clip;
        return r;
    }
    float t = cam->tan_half_fov;
    vec3 dc = v3((2.0f * nx - 1.0f) * t, (1.0f - 2.0f * ny) * t * cam->inv_aspect, 1.0f);
    vec3 oc = v3s(0.0f);
    if (cam->lens_radius > 0.0f) {
        /* thin lens: the ray through the lens point aims at where the pinhole ray meets the plane in focus */
        float2 p = square_to_uniform_disk(lens) * cam->lens_radius;
        oc = v3(p.x, p.y, 0.0f);
        dc = vmad(dc, cam->focus_distance, vneg(oc));
    }
    float inv_len = 1.0f / len3(dc);
    dc = vscale(dc, inv_len);
    vec3 X = vrow(cam->to_world[0]), Y = vrow(cam->to_world[1]), Z = vrow(cam->to_world[2]);
    vec3 dw = vmad(Z, dc.z, vmad(X, dc.x, vscale(Y, dc.y)));
    float scale = len3(dw); /* a scaled toWorld stretches distances: keep the clip planes where Nori has them */
    Ray r;
    r.o = vmad(Y, oc.y, vmad(X, oc.x, vrow(cam->to_world[3])));
    r.d = vscale(dw, 1.0f / scale);
    r.tmin = cam->near_clip / dc.z * scale;
    r.tmax = cam->far_clip / dc.z * scale;
    return r;
}

INLINE Ray camera_ray(__global const Camera* cam, float sx, float sy) {
    return camera_ray_lens(cam, sx, sy, (float2)(0.5f, 0.5f));
}

#endif
