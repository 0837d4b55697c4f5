/* Inline replacements for the cheap OpenCL builtins, for PoCL (the host defines CLRENDER_INLINE_BUILTINS when it
   builds for a PoCL device; clrender/device/program.py).

   Why: PoCL 3.0 links its builtin library after our code is optimised, and in a program of our size it leaves
   every builtin as a function call: a render_pass binary held 890 calls to sqrt, 862 to fabs and 2556 to floor,
   and a profile of the Cornell twin spent 3.5 % of its time inside _cl_sqrt and 3.5 % in _cl_vload4 alone. A
   call costs more than the instruction it wraps: every vector register live across it is spilled (all of them
   are caller-saved on x86-64). Clang's __builtin_* functions become LLVM intrinsics in the front end, so they
   compile to the instruction itself (sqrtss, andps, roundss, minss...).

   Each replacement has the builtin's OpenCL semantics for the types we use: sqrt is correctly rounded (OpenCL
   allows 3 ulp), fmin/fmax return the other operand for a NaN (llvm.minnum/maxnum, as OpenCL's), clamp is
   fmin(fmax(x, lo), hi), the scalar isfinite/isnan/isinf return 1 or 0. Transcendental functions (exp, log, pow,
   sin, ...) stay PoCL's: they are expensive either way, and their intrinsics would become calls into libm.
   Other drivers (GPUs) inline their builtins themselves and never see this file's definitions. A build with
   -DCLRENDER_BUILTIN_CALLS keeps PoCL's builtins, for measuring the difference (benchmarks/ab_pass.py). */
#ifndef CLRENDER_BUILTINS_H
#define CLRENDER_BUILTINS_H

#if defined(CLRENDER_INLINE_BUILTINS) && defined(__clang__) && !defined(CLRENDER_BUILTIN_CALLS)

#define CLR_OVERLOAD static inline __attribute__((overloadable, always_inline))

/* one scalar body, and the float2/3/4 versions component by component */
#define CLR_FLOAT_UNARY(name, expr)                                                                           \
    CLR_OVERLOAD float name(float x) { return expr; }                                                         \
    CLR_OVERLOAD float2 name(float2 v) { return (float2)(name(v.x), name(v.y)); }                           \
    CLR_OVERLOAD float3 name(float3 v) { return (float3)(name(v.x), name(v.y), name(v.z)); }                \
    CLR_OVERLOAD float4 name(float4 v) { return (float4)(name(v.x), name(v.y), name(v.z), name(v.w)); }
#define CLR_FLOAT_BINARY(name, expr)                                                                          \
    CLR_OVERLOAD float name(float x, float y) { return expr; }                                                \
    CLR_OVERLOAD float2 name(float2 a, float2 b) { return (float2)(name(a.x, b.x), name(a.y, b.y)); }        \
    CLR_OVERLOAD float3 name(float3 a, float3 b) {                                                            \
        return (float3)(name(a.x, b.x), name(a.y, b.y), name(a.z, b.z));                                     \
    }                                                                                                         \
    CLR_OVERLOAD float4 name(float4 a, float4 b) {                                                            \
        return (float4)(name(a.x, b.x), name(a.y, b.y), name(a.z, b.z), name(a.w, b.w));                     \
    }

CLR_FLOAT_UNARY(clr_sqrt, __builtin_sqrtf(x))
CLR_FLOAT_UNARY(clr_fabs, __builtin_fabsf(x))
CLR_FLOAT_UNARY(clr_floor, __builtin_floorf(x))
CLR_FLOAT_UNARY(clr_ceil, __builtin_ceilf(x))
CLR_FLOAT_UNARY(clr_rint, __builtin_rintf(x))
CLR_FLOAT_UNARY(clr_trunc, __builtin_truncf(x))
CLR_FLOAT_BINARY(clr_fmin, __builtin_fminf(x, y))
CLR_FLOAT_BINARY(clr_fmax, __builtin_fmaxf(x, y))
CLR_FLOAT_BINARY(clr_copysign, __builtin_copysignf(x, y))

CLR_OVERLOAD float clr_clamp(float x, float lo, float hi) { return clr_fmin(clr_fmax(x, lo), hi); }
CLR_OVERLOAD float3 clr_clamp(float3 x, float lo, float hi) {
    return (float3)(clr_clamp(x.x, lo, hi), clr_clamp(x.y, lo, hi), clr_clamp(x.z, lo, hi));
}
CLR_OVERLOAD int clr_clamp(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }
CLR_OVERLOAD uint clr_clamp(uint x, uint lo, uint hi) { return x < lo ? lo : (x > hi ? hi : x); }
CLR_OVERLOAD int clr_min(int a, int b) { return a < b ? a : b; }
CLR_OVERLOAD uint clr_min(uint a, uint b) { return a < b ? a : b; }
CLR_OVERLOAD float clr_min(float a, float b) { return clr_fmin(a, b); }
CLR_OVERLOAD int clr_max(int a, int b) { return a > b ? a : b; }
CLR_OVERLOAD uint clr_max(uint a, uint b) { return a > b ? a : b; }
CLR_OVERLOAD float clr_max(float a, float b) { return clr_fmax(a, b); }

/* on the bits, so that -cl-fast-relaxed-math (which lets the compiler assume finite values) cannot fold them */
CLR_OVERLOAD int clr_isfinite(float x) { return (as_uint(x) & 0x7f800000u) != 0x7f800000u ? 1 : 0; }
CLR_OVERLOAD int clr_isnan(float x) { return (as_uint(x) & 0x7fffffffu) > 0x7f800000u ? 1 : 0; }
CLR_OVERLOAD int clr_isinf(float x) { return (as_uint(x) & 0x7fffffffu) == 0x7f800000u ? 1 : 0; }

/* function-like, so a struct field of the same name (p.gaussian.floor) is left alone; PoCL's own header
   defines some of these names as macros already */
#undef sqrt
#define sqrt(...) clr_sqrt(__VA_ARGS__)
#undef fabs
#define fabs(...) clr_fabs(__VA_ARGS__)
#undef floor
#define floor(...) clr_floor(__VA_ARGS__)
#undef ceil
#define ceil(...) clr_ceil(__VA_ARGS__)
#undef rint
#define rint(...) clr_rint(__VA_ARGS__)
#undef trunc
#define trunc(...) clr_trunc(__VA_ARGS__)
#undef fmin
#define fmin(...) clr_fmin(__VA_ARGS__)
#undef fmax
#define fmax(...) clr_fmax(__VA_ARGS__)
#undef copysign
#define copysign(...) clr_copysign(__VA_ARGS__)
#undef clamp
#define clamp(...) clr_clamp(__VA_ARGS__)
#undef min
#define min(...) clr_min(__VA_ARGS__)
#undef max
#define max(...) clr_max(__VA_ARGS__)
#undef isfinite
#define isfinite(...) clr_isfinite(__VA_ARGS__)
#undef isnan
#define isnan(...) clr_isnan(__VA_ARGS__)
#undef isinf
#define isinf(...) clr_isinf(__VA_ARGS__)

#endif
#endif
