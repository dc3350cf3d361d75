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

// scalar min/max with the same meaning
inline double smin(double a, double b) { return a < b ? a : b; }
inline double smax(double a, double b) { return a > b ? a : b; }

}  // namespace dmh
