// Lanes of doubles as one machine vector (GCC / Clang vector extensions): the kernels hold
// configurations in structure-of-arrays blocks and compute W of them per instruction.
//
// W follows the instruction set the module is compiled for (CMakeLists.txt: the installing
// machine's own): 4 with AVX, else 2 (SSE2, every x86-64 CPU). Arithmetic and comparisons are
// the extensions' own operators; floor, sqrt, min, max use the matching intrinsics.
#pragma once

#include <cstdint>
#include <cstring>
#include <climits>

#if defined(__AVX__)
#include <immintrin.h>
#define DMH_W 4
#elif defined(__SSE4_1__)
#include <smmintrin.h>
#define DMH_W 2
#else
#include <emmintrin.h>
#define DMH_W 2
#endif

namespace dmh {

constexpr int W = DMH_W;
typedef double vd __attribute__((vector_size(8 * W)));
typedef int64_t vi __attribute__((vector_size(8 * W)));
typedef double vd_u __attribute__((vector_size(8 * W), aligned(8)));  // unaligned access

inline vd load(const double* p) { return *reinterpret_cast<const vd_u*>(p); }
inline void store(double* p, vd x) { *reinterpret_cast<vd_u*>(p) = x; }
inline vd splat(double x) {  // (not vd{} + x: that turns -0.0 into +0.0)
    vd r;
    for (int i = 0; i < W; ++i) r[i] = x;
    return r;
}
constexpr int64_t SIGN = INT64_MIN;  // the sign bit of a double

#if DMH_W == 4
inline vd vfloor(vd x) { return (vd)_mm256_floor_pd((__m256d)x); }
inline vd vsqrt(vd x) { return (vd)_mm256_sqrt_pd((__m256d)x); }
// min/max as numba's (LLVM minnum/maxnum under nnan): either operand when equal, no NaN here
inline vd vmin(vd a, vd b) { return (vd)_mm256_min_pd((__m256d)a, (__m256d)b); }
inline vd vmax(vd a, vd b) { return (vd)_mm256_max_pd((__m256d)a, (__m256d)b); }
inline bool any(vi m) { return !_mm256_testz_si256((__m256i)m, (__m256i)m); }
#else
#if defined(__SSE4_1__)
inline vd vfloor(vd x) { return (vd)_mm_floor_pd((__m128d)x); }
#else
inline vd vfloor(vd x) {
    vd r;
    for (int i = 0; i < W; ++i) r[i] = __builtin_floor(x[i]);
    return r;
}
#endif
inline vd vsqrt(vd x) { return (vd)_mm_sqrt_pd((__m128d)x); }
inline vd vmin(vd a, vd b) { return (vd)_mm_min_pd((__m128d)a, (__m128d)b); }
inline vd vmax(vd a, vd b) { return (vd)_mm_max_pd((__m128d)a, (__m128d)b); }
inline bool any(vi m) { return _mm_movemask_pd((__m128d)m) != 0; }
#endif

inline vd vabs(vd x) { return (vd)((vi)x & ~SIGN); }
inline vd select(vi m, vd a, vd b) { return (vd)(((vi)a & m) | ((vi)b & ~m)); }

// sin and cos of every lane (Cephes' sin.c / cos.c, Moshier: x reduced by multiples of pi/4 in
// three parts, then a degree-13 / 14 polynomial; relative error about 2e-16 for |x| < 1e9).
// A lane beyond that, or not finite, is handed to std::sin / std::cos.
inline void vsincos(vd x, vd& s, vd& c) {
    const double DP1 = 7.85398125648498535156E-1, DP2 = 3.77489470793079817668E-8,
                 DP3 = 2.69515142907905952645E-15, FOPI = 1.27323954473516268615;
    const vd ax = vabs(x);
    vd y = vfloor(ax * FOPI);
    const vd z16 = y - 16.0 * vfloor(y * (1.0 / 16.0));           // y mod 16: 0..15, exact
    vi j = (vi)(z16 + 4503599627370496.0) & 15;                      // its integer (2^52 shift)
    const vi odd = j & 1;
    j += odd;
    y += select(odd != 0, splat(1.0), splat(0.0));
    const vd r = ((ax - y * DP1) - y * DP2) - y * DP3;
    const vd zz = r * r;
    const vd ps = r + r * zz * (((((1.58962301576546568060E-10 * zz - 2.50507477628578072866E-8) * zz +
                                   2.75573136213857245213E-6) * zz - 1.98412698295895385996E-4) * zz +
                                 8.33333333332211858878E-3) * zz - 1.66666666666666307295E-1);
    const vd pc = 1.0 - 0.5 * zz + zz * zz * (((((-1.13585365213876817300E-11 * zz + 2.08757008419747316778E-9) * zz -
                                               2.75573141792967388112E-7) * zz + 2.48015872888517045348E-5) * zz -
                                             1.38888888888730564116E-3) * zz + 4.16666666666665929218E-2);
    const vi swap = (j & 2) != 0, half = (j & 4) != 0;
    const vd sin_r = select(swap, pc, ps), cos_r = select(swap, ps, pc);
    s = (vd)((vi)sin_r ^ (((vi)x ^ (half & SIGN)) & SIGN));         // sign of x, flipped past pi
    c = (vd)((vi)cos_r ^ ((half ^ swap) & SIGN));
    const vi wild = ~(ax < 1e9);                                    // also NaN
    if (any(wild))
        for (int l = 0; l < W; ++l)
            if (wild[l]) s[l] = __builtin_sin(x[l]), c[l] = __builtin_cos(x[l]);
}

// scalar min/max with the same meaning
inline double smin(double a, double b) { return a < b ? a : b; }
inline double smax(double a, double b) { return a > b ? a : b; }

}  // namespace dmh
