// Forward kinematics of a compiled chain (drake_mh.kinematics.batch.compile_chain): the world
// pose of every moving frame, for a block of configurations (lanes, structure of arrays, W at a
// time) or for one configuration. The same recursion, operations and sine/cosine as the numba
// kernels of drake_mh/kinematics/kernels.py.
#pragma once

#include <cmath>
#include <cstdint>

#include "simd.hpp"

namespace dmh {

// The chain as drake_mh.kinematics.BatchKinematics passes it: F moving frames, each with its
// parent (-1: the world), fixed rotation KR (3, 3) and offset Kp (3,) from the parent, the
// signed permutation of KR (perm[k][0] < 0: none), joint kind (0 revolute, 1 prismatic) and
// coordinate index.
struct Chain {
    int64_t F = 0;
    const int64_t* parent = nullptr;
    const double* KR = nullptr;
    const double* Kp = nullptr;
    const int64_t* perm = nullptr;
    const int64_t* kind = nullptr;
    const int64_t* qidx = nullptr;
};

// fdlibm's Cody-Waite reduction by pi/2 and its minimax polynomials on [-pi/4, pi/4]
// (__kernel_sin / __kernel_cos): drake_mh/kinematics/kernels.py, _sincos_block.
namespace fd {
constexpr double INV_PIO2 = 6.36619772367581382433e-01;
constexpr double PIO2_1 = 1.57079632673412561417e00, PIO2_2 = 6.07710050630396597660e-11,
                 PIO2_3 = 2.02226624871116645580e-21;
constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                 S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                 S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                 C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                 C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
constexpr double LARGE = 1e5;
constexpr double MAGIC = 6755399441055744.0;  // 1.5 * 2^52: x + MAGIC holds round(x) in its low bits
}  // namespace fd

// sin and cos of W angles; an angle beyond 1e5 rad is recomputed with the C library.
inline void sincos_v(vd x, vd& s_out, vd& c_out) {
    using namespace fd;
    vd nf = vfloor(x * INV_PIO2 + 0.5);
    vd r = ((x - nf * PIO2_1) - nf * PIO2_2) - nf * PIO2_3;
    vd z = r * r;
    vd sp = r + r * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    vd cp = 1.0 - 0.5 * z + z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    vi n = (vi)(nf + MAGIC);  // the integer nf in the low bits (|nf| < 2^51)
    vi odd = -(n & 1);
    vd s = select(odd, cp, sp), c = select(odd, sp, cp);
    vi flip_s = -((n >> 1) & 1), flip_c = -(((n + 1) >> 1) & 1);
    s_out = (vd)((vi)s ^ (flip_s & SIGN));
    c_out = (vd)((vi)c ^ (flip_c & SIGN));
    vi large = vabs(x) > LARGE;
    if (__builtin_expect(any(large), 0)) {
        for (int i = 0; i < W; ++i)
            if (std::fabs(x[i]) > LARGE) {
                s_out[i] = std::sin(x[i]);
                c_out[i] = std::cos(x[i]);
            }
    }
}

inline void sincos_1(double x, double& s_out, double& c_out) {
    vd s, c;
    sincos_v(splat(x), s, c);
    s_out = s[0];
    c_out = c[0];
}

// World poses of every moving frame for the lanes of a block: R (F, 3, 3, L) and p (F, 3, L),
// lane index innermost with stride L (a multiple of W); q (nq, L) the block's configurations,
// coordinate first. nv vectors of W lanes are computed (every lane of them must hold a finite q).
inline void frames_block(const Chain& c, const double* q, int64_t L, int64_t nv, double* R, double* p) {
    auto Rk = [&](int64_t k, int i, int j) { return R + ((k * 3 + i) * 3 + j) * L; };
    auto pk = [&](int64_t k, int i) { return p + (k * 3 + i) * L; };
    for (int64_t k = 0; k < c.F; ++k) {
        const int64_t a = c.parent[k];
        const double* row = q + c.qidx[k] * L;
        const bool revolute = c.kind[k] == 0;
        const double* KR = c.KR + 9 * k;
        const double* Kp = c.Kp + 3 * k;
        const int64_t* perm = c.perm + 3 * k;
        for (int64_t v = 0; v < nv; ++v) {
            const int64_t o = v * W;
            vd sn{}, cs{};
            if (revolute) sincos_v(load(row + o), sn, cs);
            if (a >= 0) {
                for (int i = 0; i < 3; ++i)
                    store(pk(k, i) + o, load(pk(a, i) + o) + load(Rk(a, i, 0) + o) * Kp[0] +
                                            load(Rk(a, i, 1) + o) * Kp[1] + load(Rk(a, i, 2) + o) * Kp[2]);
            }
            if (a >= 0 && revolute && perm[0] >= 0) {
                const int64_t s0 = perm[0], s1 = perm[1], s2 = perm[2];
                const double g0 = KR[s0 * 3 + 0], g1 = KR[s1 * 3 + 1], g2 = KR[s2 * 3 + 2];
                for (int i = 0; i < 3; ++i) {
                    vd r0 = g0 * load(Rk(a, i, s0) + o);
                    vd r1 = g1 * load(Rk(a, i, s1) + o);
                    store(Rk(k, i, 2) + o, g2 * load(Rk(a, i, s2) + o));
                    store(Rk(k, i, 0) + o, r0 * cs + r1 * sn);
                    store(Rk(k, i, 1) + o, r1 * cs - r0 * sn);
                }
                continue;
            }
            if (a < 0) {
                for (int i = 0; i < 3; ++i) {
                    store(pk(k, i) + o, splat(Kp[i]));
                    for (int j = 0; j < 3; ++j) store(Rk(k, i, j) + o, splat(KR[i * 3 + j]));
                }
            } else if (perm[0] >= 0) {
                for (int j = 0; j < 3; ++j) {
                    const int64_t src = perm[j];
                    const double sg = KR[src * 3 + j];
                    for (int i = 0; i < 3; ++i) store(Rk(k, i, j) + o, sg * load(Rk(a, i, src) + o));
                }
            } else {
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        store(Rk(k, i, j) + o, load(Rk(a, i, 0) + o) * KR[j] + load(Rk(a, i, 1) + o) * KR[3 + j] +
                                                   load(Rk(a, i, 2) + o) * KR[6 + j]);
            }
            if (revolute) {
                for (int i = 0; i < 3; ++i) {
                    vd r0 = load(Rk(k, i, 0) + o), r1 = load(Rk(k, i, 1) + o);
                    store(Rk(k, i, 0) + o, r0 * cs + r1 * sn);
                    store(Rk(k, i, 1) + o, r1 * cs - r0 * sn);
                }
            } else {
                for (int i = 0; i < 3; ++i) store(pk(k, i) + o, load(pk(k, i) + o) + load(Rk(k, i, 2) + o) * load(row + o));
            }
        }
    }
}

// The same for one configuration q (nq,) read with stride qs (elements): R (F, 3, 3), p (F, 3).
inline void frames_one(const Chain& c, const double* q, int64_t qs, double* R, double* p) {
    for (int64_t k = 0; k < c.F; ++k) {
        const int64_t a = c.parent[k];
        const double* KR = c.KR + 9 * k;
        const double* Kp = c.Kp + 3 * k;
        const int64_t* perm = c.perm + 3 * k;
        double* Rk = R + 9 * k;
        double* pk = p + 3 * k;
        const double x = q[c.qidx[k] * qs];
        const bool revolute = c.kind[k] == 0;
        double sn = 0.0, cs = 0.0;
        if (revolute) sincos_1(x, sn, cs);
        if (a < 0) {
            for (int i = 0; i < 3; ++i) {
                pk[i] = Kp[i];
                for (int j = 0; j < 3; ++j) Rk[i * 3 + j] = KR[i * 3 + j];
            }
        } else {
            const double* Ra = R + 9 * a;
            const double* pa = p + 3 * a;
            for (int i = 0; i < 3; ++i)
                pk[i] = pa[i] + Ra[i * 3] * Kp[0] + Ra[i * 3 + 1] * Kp[1] + Ra[i * 3 + 2] * Kp[2];
            if (perm[0] >= 0) {
                for (int j = 0; j < 3; ++j) {
                    const int64_t src = perm[j];
                    const double sg = KR[src * 3 + j];
                    for (int i = 0; i < 3; ++i) Rk[i * 3 + j] = sg * Ra[i * 3 + src];
                }
            } else {
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        Rk[i * 3 + j] = Ra[i * 3] * KR[j] + Ra[i * 3 + 1] * KR[3 + j] + Ra[i * 3 + 2] * KR[6 + j];
            }
        }
        if (revolute) {
            for (int i = 0; i < 3; ++i) {
                const double r0 = Rk[i * 3], r1 = Rk[i * 3 + 1];
                Rk[i * 3] = r0 * cs + r1 * sn;
                Rk[i * 3 + 1] = r1 * cs - r0 * sn;
            }
        } else {
            for (int i = 0; i < 3; ++i) pk[i] += Rk[i * 3 + 2] * x;
        }
    }
}

}  // namespace dmh
