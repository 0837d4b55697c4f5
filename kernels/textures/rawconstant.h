/* Mitsuba 3's rawconstant (clrender/textures/rawconstant.py): its value wherever it is looked up, unconverted.
   Row: p.rawconstant.value = (value, 0). */
#ifndef CLRENDER_TEXTURES_RAWCONSTANT_H
#define CLRENDER_TEXTURES_RAWCONSTANT_H

INLINE vec3 rawconstant_eval(__global const Texture* t, float2 uv) {
    return vrow(t->p.rawconstant.value);
}

#endif
