/* The integrator chosen at build time: the host passes -DINTEGRATOR=<name> and we include
   kernels/integrators/<name>.h, which defines Li(scene, ray, sampler). Entry points include this. */
#ifndef CLRENDER_LI_H
#define CLRENDER_LI_H
#include "math.h"
#include "rng.h"
#include "camera.h"
#include "scene.h"

#define STR_(x) #x
#define STR(x) STR_(x)
#define INTEGRATOR_HEADER(name) STR(integrators/name.h)
#include INTEGRATOR_HEADER(INTEGRATOR)

#endif
