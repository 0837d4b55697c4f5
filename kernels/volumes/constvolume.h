/* constvolume (clrender/volumes/constvolume.py): the same value everywhere. Row: p.constvolume.value (xyz). */
#ifndef CLRENDER_VOLUMES_CONSTVOLUME_H
#define CLRENDER_VOLUMES_CONSTVOLUME_H

INLINE vec3 constvolume_eval(const SceneData* sd, __global const Volume* v, vec3 p) {
    return vrow(v->p.constvolume.value);
}
#endif
