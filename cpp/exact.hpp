// One configuration's exact link-obstacle and capsule self-pair distances: exact_pairs of
// drake_mh/scene/kernels/exact.py with the golden-section search and closed-form SDFs of
// drake_mh/scene/segment_distance.py, step for step (the array layouts, the pruning and the
// statuses are described in exact.py). Compiled without floating-point contraction, as numba
// compiles those kernels, so the two give the same numbers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "gjk.hpp"
#include "kinematics.hpp"

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")

namespace dmh {
namespace exact {

constexpr int64_t SPHERE = 0, BOX = 1, CYLINDER = 2, CAPSULE = 3;  // segment_distance.py
constexpr int64_t LINK_DRAKE = 0, LINK_POINT = 1, LINK_SEGMENT = 2, LINK_GJK = 3;
constexpr int64_t SKIPPED = 0, EXACT = 1, NEEDS_DRAKE = 2;
constexpr double GOLDEN = 0.6180339887498949;
constexpr int ITERATIONS = 90;
constexpr int64_t GW = 20, OW = 20;  // columns of g_float and o_float

// Signed distance of (x, y, z) in the obstacle frame to a sphere, box, cylinder or capsule
// (segment_distance.py _sdf; dims as there).
inline double sdf(int64_t kind, const double* dims, double x, double y, double z) {
    if (kind == SPHERE) return std::sqrt(x * x + y * y + z * z) - dims[0];
    if (kind == BOX) {
        const double dx = std::fabs(x) - dims[0], dy = std::fabs(y) - dims[1], dz = std::fabs(z) - dims[2];
        const double ox = std::max(dx, 0.0), oy = std::max(dy, 0.0), oz = std::max(dz, 0.0);
        return std::sqrt(ox * ox + oy * oy + oz * oz) + std::min(std::max(dx, std::max(dy, dz)), 0.0);
    }
    if (kind == CYLINDER) {
        const double dr = std::sqrt(x * x + y * y) - dims[0], da = std::fabs(z) - dims[1];
        const double orr = std::max(dr, 0.0), oa = std::max(da, 0.0);
        return std::sqrt(orr * orr + oa * oa) + std::min(std::max(dr, da), 0.0);
    }
    const double zc = std::min(std::max(z, -dims[1]), dims[1]);
    return std::sqrt(x * x + y * y + (z - zc) * (z - zc)) - dims[0];
}

// (t*, sdf*): the minimum of the SDF along a -> b (obstacle frame) by golden-section search and
// the two ends (segment_distance.py segment_min_sdf, the same iterations and arithmetic).
inline double golden(int64_t kind, const double* dims, const double* a, const double* b, double& best_t) {
    const double a0 = a[0], a1 = a[1], a2 = a[2], d0 = b[0] - a0, d1 = b[1] - a1, d2 = b[2] - a2;
    double lo = 0.0, hi = 1.0;
    double t1 = hi - GOLDEN * (hi - lo), t2 = lo + GOLDEN * (hi - lo);
    double f1 = sdf(kind, dims, a0 + t1 * d0, a1 + t1 * d1, a2 + t1 * d2);
    double f2 = sdf(kind, dims, a0 + t2 * d0, a1 + t2 * d1, a2 + t2 * d2);
    for (int it = 0; it < ITERATIONS; ++it) {
        if (f1 <= f2) {
            hi = t2, t2 = t1, f2 = f1;
            t1 = hi - GOLDEN * (hi - lo);
            f1 = sdf(kind, dims, a0 + t1 * d0, a1 + t1 * d1, a2 + t1 * d2);
        } else {
            lo = t1, t1 = t2, f1 = f2;
            t2 = lo + GOLDEN * (hi - lo);
            f2 = sdf(kind, dims, a0 + t2 * d0, a1 + t2 * d1, a2 + t2 * d2);
        }
    }
    double best_f;
    if (f1 <= f2) best_t = t1, best_f = f1;
    else best_t = t2, best_f = f2;
    double f = sdf(kind, dims, a0, a1, a2);
    if (f < best_f) best_t = 0.0, best_f = f;
    f = sdf(kind, dims, a0 + d0, a1 + d1, a2 + d2);
    if (f < best_f) best_t = 1.0, best_f = f;
    return best_f;
}

// Unit numerical gradient g (3,) of the SDF at p (segment_distance.py _gradient).
inline void gradient(int64_t kind, const double* dims, const double* p, double* g) {
    const double h = 1e-7;
    for (int i = 0; i < 3; ++i) {
        double q1[3] = {p[0], p[1], p[2]}, q2[3] = {p[0], p[1], p[2]};
        q1[i] += h;
        q2[i] -= h;
        g[i] = (sdf(kind, dims, q1[0], q1[1], q1[2]) - sdf(kind, dims, q2[0], q2[1], q2[2])) / (2 * h);
    }
    const double n = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (n > 0) g[0] /= n, g[1] /= n, g[2] /= n;
}

// Unit normal n of a box or cylinder at p (obstacle frame, SDF value f) and its point c nearest
// p: clamping outside, the numerical gradient inside (exact.py _normal_and_closest).
inline void normal_and_closest(int64_t kind, const double* dims, const double* p, double f, double* n, double* c) {
    if (f > 0.0) {
        if (kind == BOX) {
            for (int j = 0; j < 3; ++j) c[j] = std::min(std::max(p[j], -dims[j]), dims[j]);
        } else {
            const double rho = std::sqrt(p[0] * p[0] + p[1] * p[1]);
            const double scale = rho > 0.0 ? std::min(rho, dims[0]) / rho : 0.0;
            c[0] = scale * p[0], c[1] = scale * p[1];
            c[2] = std::min(std::max(p[2], -dims[1]), dims[1]);
        }
        const double e0 = p[0] - c[0], e1 = p[1] - c[1], e2 = p[2] - c[2];
        const double norm = std::sqrt(e0 * e0 + e1 * e1 + e2 * e2);
        if (norm > 0.0) {
            for (int j = 0; j < 3; ++j) n[j] = (p[j] - c[j]) / norm;
            return;
        }
    }
    gradient(kind, dims, p, n);
    for (int j = 0; j < 3; ++j) c[j] = p[j] - f * n[j];
}

// Closest points c1 on p1-q1 and c2 on p2-q2, returns their distance (Ericson, Real-Time
// Collision Detection, sec. 5.1.9; exact.py closest_segments).
inline double closest_segments(const double* p1, const double* q1, const double* p2, const double* q2, double* c1,
                               double* c2) {
    const double d10 = q1[0] - p1[0], d11 = q1[1] - p1[1], d12 = q1[2] - p1[2];
    const double d20 = q2[0] - p2[0], d21 = q2[1] - p2[1], d22 = q2[2] - p2[2];
    const double r0 = p1[0] - p2[0], r1 = p1[1] - p2[1], r2 = p1[2] - p2[2];
    const double a = d10 * d10 + d11 * d11 + d12 * d12, e = d20 * d20 + d21 * d21 + d22 * d22;
    const double f = d20 * r0 + d21 * r1 + d22 * r2;
    const double eps = 1e-30;
    auto clamp01 = [](double x) { return std::min(std::max(x, 0.0), 1.0); };
    double s, t;
    if (a <= eps && e <= eps) {
        s = t = 0.0;
    } else if (a <= eps) {
        s = 0.0;
        t = clamp01(f / e);
    } else {
        const double c = d10 * r0 + d11 * r1 + d12 * r2;
        if (e <= eps) {
            t = 0.0;
            s = clamp01(-c / a);
        } else {
            const double b = d10 * d20 + d11 * d21 + d12 * d22, denom = a * e - b * b;
            s = denom > 1e-15 * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = clamp01((b - c) / a);
            }
        }
    }
    c1[0] = p1[0] + s * d10, c1[1] = p1[1] + s * d11, c1[2] = p1[2] + s * d12;
    c2[0] = p2[0] + t * d20, c2[1] = p2[1] + t * d21, c2[2] = p2[2] + t * d22;
    const double e0 = c1[0] - c2[0], e1 = c1[1] - c2[1], e2 = c1[2] - c2[2];
    return std::sqrt(e0 * e0 + e1 * e1 + e2 * e2);
}

// The arrays of exact.py (its module docstring): the robot's geometries, the obstacles, the
// hulls' vertices, the self pairs, and the outputs.
struct Pairs {
    Chain chain;
    int64_t nq = 0, G = 0, K = 0, S = 0;
    const int64_t *g_int, *o_int, *self_pairs;
    const double *g_float, *o_float, *vertices;
    double *R_WG, *p_WG, *out;
    int64_t *status, *need, *order;
};

// out = R_WO^T (x - p_WO) of obstacle row o (o_float).
inline void to_obstacle(const double* o, const double* x, double* out) {
    const double d0 = x[0] - o[9], d1 = x[1] - o[10], d2 = x[2] - o[11];
    for (int i = 0; i < 3; ++i) out[i] = o[i] * d0 + o[3 + i] * d1 + o[6 + i] * d2;
}

inline void to_world(const double* o, const double* x, double* out) {
    for (int i = 0; i < 3; ++i) out[i] = o[9 + i] + o[3 * i] * x[0] + o[3 * i + 1] * x[1] + o[3 * i + 2] * x[2];
}

inline void rotate(const double* o, const double* x, double* out) {
    for (int i = 0; i < 3; ++i) out[i] = o[3 * i] * x[0] + o[3 * i + 1] * x[1] + o[3 * i + 2] * x[2];
}

// Axis ends of a capsule link g (a point twice for a sphere link), in W.
inline void segment_ends(const Pairs& P, int64_t g, double* a, double* b) {
    const double h = P.g_float[g * GW + 12];
    for (int i = 0; i < 3; ++i) {
        a[i] = P.p_WG[3 * g + i] - h * P.R_WG[9 * g + 3 * i + 2];
        b[i] = P.p_WG[3 * g + i] + h * P.R_WG[9 * g + 3 * i + 2];
    }
}

// n = (c_link - c_other) / |...| (z when they coincide).
inline void unit(const double* c_link, const double* c_other, double* n) {
    double norm = 0.0;
    for (int j = 0; j < 3; ++j) n[j] = c_link[j] - c_other[j], norm += n[j] * n[j];
    norm = std::sqrt(norm);
    if (norm > 0.0) n[0] /= norm, n[1] /= norm, n[2] /= norm;
    else n[0] = 0.0, n[1] = 0.0, n[2] = 1.0;
}

// Row i: distance, the points pushed out of the cores by the radii along the normal n.
inline void write(double* out, int64_t i, double d, const double* c_link, double r_link, const double* c_other,
                  double r_other, const double* n) {
    double* row = out + 10 * i;
    row[0] = d;
    for (int j = 0; j < 3; ++j) {
        row[1 + j] = c_link[j] - r_link * n[j];
        row[4 + j] = c_other[j] + r_other * n[j];
        row[7 + j] = n[j];
    }
}

// World poses R_WG (G, 3, 3), p_WG (G, 3); false if q is not finite (exact.py geometry_poses).
inline bool geometry_poses(const Pairs& P, const double* q, int64_t qs, std::vector<double>& R,
                           std::vector<double>& p) {
    for (int64_t j = 0; j < P.nq; ++j)
        if (!std::isfinite(q[j * qs])) return false;
    R.resize(9 * std::max<int64_t>(P.chain.F, 1));
    p.resize(3 * std::max<int64_t>(P.chain.F, 1));
    frames_one(P.chain, q, qs, R.data(), p.data());
    for (int64_t g = 0; g < P.G; ++g) {
        const int64_t a = P.g_int[g * 5];
        const double* f = P.g_float + g * GW;
        for (int i = 0; i < 3; ++i) {
            if (a < 0) {
                P.p_WG[3 * g + i] = f[9 + i];
                for (int j = 0; j < 3; ++j) P.R_WG[9 * g + 3 * i + j] = f[3 * i + j];
            } else {
                const double* Ra = R.data() + 9 * a + 3 * i;
                P.p_WG[3 * g + i] = p[3 * a + i] + Ra[0] * f[9] + Ra[1] * f[10] + Ra[2] * f[11];
                for (int j = 0; j < 3; ++j)
                    P.R_WG[9 * g + 3 * i + j] = Ra[0] * f[j] + Ra[1] * f[3 + j] + Ra[2] * f[6 + j];
            }
        }
    }
    return true;
}

// Cheap lower bound of pair (g, k): the obstacle's SDF at the bounding centre minus its radius.
inline double lower_bound(const Pairs& P, int64_t g, int64_t k) {
    const double* f = P.g_float + g * GW;
    const double* R = P.R_WG + 9 * g;
    double c[3], c_O[3];
    for (int i = 0; i < 3; ++i)
        c[i] = P.p_WG[3 * g + i] + R[3 * i] * f[16] + R[3 * i + 1] * f[17] + R[3 * i + 2] * f[18];
    const double* o = P.o_float + k * OW;
    to_obstacle(o, c, c_O);
    return sdf(P.o_int[2 * k], o + 12, c_O[0], c_O[1], c_O[2]) - f[19];
}

// Exact distance of link geometry g and obstacle k into row i of out; returns the status
// (exact.py pair_distance).
inline int64_t pair_distance(const Pairs& P, int64_t g, int64_t k, int64_t i, double tol) {
    const int64_t kind = P.g_int[g * 5 + 1], sdf_kind = P.o_int[2 * k], core_kind = P.o_int[2 * k + 1];
    const double* o = P.o_float + k * OW;
    const double* dims = o + 12;
    const double* gf = P.g_float + g * GW;
    double r_link = gf[15];
    double a[3], b[3], c_link[3], c_other[3], n[3], a_O[3], b_O[3], p_O[3], n_O[3];
    if ((kind == LINK_POINT || kind == LINK_SEGMENT) && core_kind != gjk::HULL) {
        segment_ends(P, g, a, b);
        if (sdf_kind == BOX || sdf_kind == CYLINDER) {
            to_obstacle(o, a, a_O);
            double f;
            if (kind == LINK_POINT) {
                f = sdf(sdf_kind, dims, a_O[0], a_O[1], a_O[2]);
                for (int j = 0; j < 3; ++j) p_O[j] = a_O[j];
            } else {
                to_obstacle(o, b, b_O);
                double t;
                f = golden(sdf_kind, dims, a_O, b_O, t);
                for (int j = 0; j < 3; ++j) p_O[j] = a_O[j] + t * (b_O[j] - a_O[j]);
            }
            normal_and_closest(sdf_kind, dims, p_O, f, a_O, n_O);  // a_O: the normal in O
            to_world(o, n_O, c_other);
            to_world(o, p_O, c_link);
            rotate(o, a_O, n);
            write(P.out, i, f - r_link, c_link, r_link, c_other, 0.0, n);
            return (f >= 0.0 || kind == LINK_POINT) ? EXACT : NEEDS_DRAKE;
        }
        const double h = o[15];  // a sphere or capsule obstacle: its axis in W
        for (int j = 0; j < 3; ++j) {
            a_O[j] = o[9 + j] - h * o[3 * j + 2];
            b_O[j] = o[9 + j] + h * o[3 * j + 2];
        }
        const double core = closest_segments(a, b, a_O, b_O, c_link, c_other);
        unit(c_link, c_other, n);
        const double r_other = o[18];
        write(P.out, i, core - r_link - r_other, c_link, r_link, c_other, r_other, n);
        return EXACT;
    }
    if (kind != LINK_POINT && kind != LINK_SEGMENT) r_link = 0.0;  // certified GJK in the obstacle frame
    const double* R = P.R_WG + 9 * g;
    double R_OG[9];
    for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) R_OG[3 * r + s] = o[r] * R[s] + o[3 + r] * R[3 + s] + o[6 + r] * R[6 + s];
    for (int j = 0; j < 3; ++j) c_link[j] = P.p_WG[3 * g + j];
    to_obstacle(o, c_link, p_O);
    double res[8];
    const int status = gjk::distance(P.g_int[g * 5 + 4], gf + 12, R_OG, p_O, P.vertices, P.g_int[g * 5 + 2],
                                     P.g_int[g * 5 + 3], core_kind, o + 15, tol, res);
    if (status == gjk::INTERSECTING || (status == gjk::NOT_CONVERGED && res[0] <= tol)) {
        P.out[10 * i] = std::numeric_limits<double>::infinity();  // overlapping cores: Drake's penetration depth
        return NEEDS_DRAKE;
    }
    const double r_other = o[18];
    to_world(o, res + 2, c_link);
    to_world(o, res + 5, c_other);
    unit(c_link, c_other, n);
    write(P.out, i, res[0] - r_other - r_link, c_link, r_link, c_other, r_other, n);
    return EXACT;
}

// Every link-obstacle pair and self pair of q (nq,), stride qs (exact.py exact_pairs): returns
// the smallest distance found and writes the numbers of pairs listed in need and of rows in
// order; (nan, -1, 0) when q is not finite.
inline double exact_pairs(const Pairs& P, const double* q, int64_t qs, double max_distance, bool min_only, double tol,
                          int64_t& n_need, int64_t& n_rows) {
    std::vector<double> R, p;
    n_need = 0, n_rows = 0;
    if (!geometry_poses(P, q, qs, R, p)) {
        n_need = -1;
        return std::numeric_limits<double>::quiet_NaN();
    }
    const int64_t G = P.G, K = P.K, n = G * K + P.S;
    double best = std::numeric_limits<double>::infinity();
    for (int64_t s = 0; s < P.S; ++s) {
        const int64_t i = G * K + s, ga = P.self_pairs[2 * s], gb = P.self_pairs[2 * s + 1];
        double a[3], b[3], c[3], d[3], c1[3], c2[3], nn[3];
        segment_ends(P, ga, a, b);
        segment_ends(P, gb, c, d);
        const double core = closest_segments(a, b, c, d, c1, c2);
        unit(c1, c2, nn);
        const double ra = P.g_float[ga * GW + 15], rb = P.g_float[gb * GW + 15];
        write(P.out, i, core - ra - rb, c1, ra, c2, rb, nn);
        P.status[i] = EXACT;
        best = std::min(best, P.out[10 * i]);
    }
    std::vector<int64_t> cand;
    std::vector<double> bound;
    cand.reserve(G * K), bound.reserve(G * K);
    for (int64_t g = 0; g < G; ++g) {
        const int64_t link = P.g_int[g * 5 + 1];
        for (int64_t k = 0; k < K; ++k) {
            const int64_t i = g * K + k, core_kind = P.o_int[2 * k + 1];
            P.status[i] = SKIPPED;
            if (link == LINK_DRAKE) continue;
            const bool cheap = (link == LINK_POINT && core_kind != gjk::HULL) ||
                               (link == LINK_SEGMENT && core_kind <= gjk::SEGMENT);
            if (cheap) {
                P.status[i] = pair_distance(P, g, k, i, tol);
                best = std::min(best, P.out[10 * i]);
                continue;
            }
            const double lb = lower_bound(P, g, k);
            if (lb > max_distance) continue;
            cand.push_back(i);
            bound.push_back(lb);
        }
    }
    const size_t n_cand = cand.size();
    std::vector<int64_t> by_bound(n_cand);
    std::iota(by_bound.begin(), by_bound.end(), 0);
    if (min_only)
        std::stable_sort(by_bound.begin(), by_bound.end(), [&](int64_t x, int64_t y) { return bound[x] < bound[y]; });
    for (size_t j = 0; j < n_cand; ++j) {
        const int64_t i = cand[by_bound[j]];
        if (min_only && bound[by_bound[j]] >= best) break;
        const int64_t st = pair_distance(P, i / K, i % K, i, tol);
        P.status[i] = st;
        if (st == NEEDS_DRAKE) P.need[n_need++] = i;
        best = std::min(best, P.out[10 * i]);
    }
    if (!min_only) {
        for (int64_t i = 0; i < n; ++i)
            if (P.status[i] == EXACT && P.out[10 * i] <= max_distance) P.order[n_rows++] = i;
        std::stable_sort(P.order, P.order + n_rows,
                         [&](int64_t x, int64_t y) { return P.out[10 * x] < P.out[10 * y]; });
    }
    return best;
}

}  // namespace exact
}  // namespace dmh

#pragma GCC pop_options
