// Lower bounds of a geometry-obstacle signed distance where the sphere model reports
// penetration: correct_clearances of drake_mh/scene/penetration.py and what it calls, step for
// step (the bounds and why they hold are described there). Compiled without floating-point
// contraction, as numba compiles that kernel, so the two give the same numbers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "exact.hpp"
#include "spheres.hpp"

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")

namespace dmh {
namespace penetration {

using exact::CAPSULE;
using exact::SPHERE;

// Rows of 3 (vertices, normals, edges) and their number.
struct Rows {
    const double* x = nullptr;
    int64_t n = 0;
    const double* operator[](int64_t i) const { return x + 3 * i; }
};

// Separating-axis value of the segment a-b against conv(corners): the largest gap over the face
// normals and the segment x edge directions (penetration.py _sat_segment).
inline double sat_segment(const double* a, const double* b, Rows corners, Rows normals, Rows edges) {
    const double d0 = b[0] - a[0], d1 = b[1] - a[1], d2 = b[2] - a[2];
    double best = -INF;
    for (int64_t m = 0; m < normals.n + edges.n; ++m) {
        double u0, u1, u2;
        if (m < normals.n) {
            u0 = normals[m][0], u1 = normals[m][1], u2 = normals[m][2];
        } else {
            const double* e = edges[m - normals.n];
            u0 = d1 * e[2] - d2 * e[1], u1 = d2 * e[0] - d0 * e[2], u2 = d0 * e[1] - d1 * e[0];
        }
        const double norm = std::sqrt(u0 * u0 + u1 * u1 + u2 * u2);
        if (norm <= 1e-9) continue;
        u0 = u0 / norm, u1 = u1 / norm, u2 = u2 / norm;
        const double pa = u0 * a[0] + u1 * a[1] + u2 * a[2], pb = u0 * b[0] + u1 * b[1] + u2 * b[2];
        const double lo_s = std::min(pa, pb), hi_s = std::max(pa, pb);
        double lo_o = INF, hi_o = -INF;
        for (int64_t v = 0; v < corners.n; ++v) {
            const double p = u0 * corners[v][0] + u1 * corners[v][1] + u2 * corners[v][2];
            lo_o = std::min(lo_o, p);
            hi_o = std::max(hi_o, p);
        }
        best = std::max(best, std::max(lo_o - hi_s, lo_s - hi_o));
    }
    return best;
}

// A lower bound of the distance between a capsule core (pts (4, 3): the origin and unit-axis
// tips of G in W) and the obstacle (penetration.py _segment_bound).
inline double segment_bound(int64_t kind, const double* dims, const double* R_WO, const double* p_WO,
                            const double* pts, double half_length, double radius, Rows corners, Rows normals,
                            Rows edges) {
    double a[3], b[3];
    for (int i = 0; i < 3; ++i) {
        double c = 0.0, z = 0.0;
        for (int j = 0; j < 3; ++j) {
            c += R_WO[3 * j + i] * (pts[j] - p_WO[j]);
            z += R_WO[3 * j + i] * (pts[9 + j] - pts[j]);
        }
        a[i] = c - half_length * z;
        b[i] = c + half_length * z;
    }
    if (kind == SPHERE || kind == CAPSULE) {  // the closest points of the axis and the obstacle's core
        const double lo[3] = {0.0, 0.0, -dims[1]}, hi[3] = {0.0, 0.0, dims[1]};
        double c1[3], c2[3];
        return exact::closest_segments(a, b, lo, hi, c1, c2) - dims[0] - radius;
    }
    double t, f = exact::golden(kind, dims, a, b, t);
    if (f <= 0.0) f = sat_segment(a, b, corners, normals, edges);
    return f - radius;
}

// Gap between the projections of conv(VH) and conv(VO) on the unit axis u.
inline double gap(double u0, double u1, double u2, Rows VH, Rows VO) {
    double lo_h = INF, hi_h = -INF, lo_o = INF, hi_o = -INF;
    for (int64_t v = 0; v < VH.n; ++v) {
        const double p = u0 * VH[v][0] + u1 * VH[v][1] + u2 * VH[v][2];
        lo_h = std::min(lo_h, p), hi_h = std::max(hi_h, p);
    }
    for (int64_t v = 0; v < VO.n; ++v) {
        const double p = u0 * VO[v][0] + u1 * VO[v][1] + u2 * VO[v][2];
        lo_o = std::min(lo_o, p), hi_o = std::max(hi_o, p);
    }
    return std::max(lo_o - hi_h, lo_h - hi_o);
}

// Separating-axis lower bound of the distance between conv(VH) and conv(VO), or +inf where it
// cannot lower stop (penetration.py _sat).
inline double sat(Rows VH, Rows NH, const double* OH, Rows EH, Rows VO, Rows NO, Rows EO, double stop, bool certain) {
    double best = -INF;
    for (int64_t m = 0; m < NH.n; ++m) {  // H's facet planes: O beyond facet m
        double lo_o = INF;
        for (int64_t v = 0; v < VO.n; ++v)
            lo_o = std::min(lo_o, NH[m][0] * VO[v][0] + NH[m][1] * VO[v][1] + NH[m][2] * VO[v][2]);
        best = std::max(best, lo_o + OH[m]);
        if (best >= stop) return INF;
    }
    for (int64_t m = 0; m < NO.n; ++m) {
        best = std::max(best, gap(NO[m][0], NO[m][1], NO[m][2], VH, VO));
        if (best >= stop) return INF;
    }
    if (!certain)
        for (int64_t e = 0; e < EH.n; ++e)
            for (int64_t f = 0; f < EO.n; ++f) {
                const double u0 = EH[e][1] * EO[f][2] - EH[e][2] * EO[f][1];
                const double u1 = EH[e][2] * EO[f][0] - EH[e][0] * EO[f][2];
                const double u2 = EH[e][0] * EO[f][1] - EH[e][1] * EO[f][0];
                const double norm = std::sqrt(u0 * u0 + u1 * u1 + u2 * u2);
                if (norm <= 1e-9) continue;
                best = std::max(best, gap(u0 / norm, u1 / norm, u2 / norm, VH, VO));
                if (best >= stop) return INF;
            }
    return best;
}

// Whether the segment a -> b meets the polytope NH p + OH <= 0 (penetration.py _segment_hits).
inline bool segment_hits(const double* a, const double* b, Rows NH, const double* OH) {
    double lo = 0.0, hi = 1.0;
    for (int64_t m = 0; m < NH.n; ++m) {
        const double fa = NH[m][0] * a[0] + NH[m][1] * a[1] + NH[m][2] * a[2] + OH[m];
        const double fb = NH[m][0] * b[0] + NH[m][1] * b[1] + NH[m][2] * b[2] + OH[m];
        if (fb < fa) lo = std::max(lo, fa / (fa - fb));
        else if (fb > fa) hi = std::min(hi, fa / (fa - fb));
        else if (fa > 0) return false;
    }
    return lo <= hi;
}

// A lower bound of the distance between a polytope core (VH, NH, OH, EH in G at R_WG, p_WG)
// and an obstacle, or +inf where the spheres' value needs no correction (penetration.py
// _polytope_bound); VO, NO, EO workspaces.
inline double polytope_bound(int64_t kind, const double* dims, const double* R_WO, const double* p_WO,
                             const double* R_WG, const double* p_WG, Rows VH, Rows NH, const double* OH, Rows EH,
                             double excess, Rows corners, Rows normals, Rows edges, double sphere_value, double* VO,
                             double* NO, double* EO) {
    double R_GO[9], p_GO[3];
    for (int i = 0; i < 3; ++i) {
        p_GO[i] = 0.0;
        for (int j = 0; j < 3; ++j) p_GO[i] += R_WG[3 * j + i] * (p_WO[j] - p_WG[j]);
        for (int k = 0; k < 3; ++k) {
            R_GO[3 * i + k] = 0.0;
            for (int j = 0; j < 3; ++j) R_GO[3 * i + k] += R_WG[3 * j + i] * R_WO[3 * j + k];
        }
    }
    if (kind == SPHERE) {  // exact depth of a centre inside; one outside needs nothing
        double depth = -INF;
        for (int64_t m = 0; m < NH.n; ++m)
            depth = std::max(depth, NH[m][0] * p_GO[0] + NH[m][1] * p_GO[1] + NH[m][2] * p_GO[2] + OH[m]);
        return depth < 0 ? depth - dims[0] : INF;
    }
    if (kind == CAPSULE) {  // an axis that misses H meets s <= d already
        for (int i = 0; i < 3; ++i) {
            VO[i] = p_GO[i] - dims[1] * R_GO[3 * i + 2];
            VO[3 + i] = p_GO[i] + dims[1] * R_GO[3 * i + 2];
            EO[i] = VO[3 + i] - VO[i];
        }
        if (!segment_hits(VO, VO + 3, NH, OH)) return INF;
        return sat(VH, NH, OH, EH, Rows{VO, 2}, Rows{NO, 0}, Rows{EO, 1}, sphere_value + dims[0], false) - dims[0];
    }
    for (int64_t v = 0; v < corners.n; ++v)  // box, cylinder prism: both polytopes' axes
        for (int i = 0; i < 3; ++i)
            VO[3 * v + i] = p_GO[i] + R_GO[3 * i] * corners[v][0] + R_GO[3 * i + 1] * corners[v][1] +
                            R_GO[3 * i + 2] * corners[v][2];
    for (int64_t m = 0; m < normals.n; ++m)
        for (int i = 0; i < 3; ++i)
            NO[3 * m + i] =
                R_GO[3 * i] * normals[m][0] + R_GO[3 * i + 1] * normals[m][1] + R_GO[3 * i + 2] * normals[m][2];
    for (int64_t m = 0; m < edges.n; ++m)
        for (int i = 0; i < 3; ++i)
            EO[3 * m + i] = R_GO[3 * i] * edges[m][0] + R_GO[3 * i + 1] * edges[m][1] + R_GO[3 * i + 2] * edges[m][2];
    return sat(VH, NH, OH, EH, Rows{VO, corners.n}, Rows{NO, normals.n}, Rows{EO, edges.n}, sphere_value,
               sphere_value < -excess);
}

// Signed distance of the world point (x, y, z) to an obstacle at R, p (dims d).
inline double sdf_at(int64_t kind, const double* d, const double* R, const double* p, double x, double y, double z) {
    const double dx = x - p[0], dy = y - p[1], dz = z - p[2];
    return exact::sdf(kind, d, R[0] * dx + R[3] * dy + R[6] * dz, R[1] * dx + R[4] * dy + R[7] * dz,
                      R[2] * dx + R[5] * dy + R[8] * dz);
}

// The arrays of correct_clearances (penetration.py, its docstring and core_arrays).
struct Cores {
    int64_t n = 0, K = 0, G = 0, Vc = 0, Fn = 0, Ee = 0;  // Vc, Fn, Ee: padded widths of corners, normals, edges
    int64_t ps[3] = {0, 0, 0};  // points_W's strides (elements): it is read in place, whatever its layout
    double* values;
    const double *points_W, *radii, *c_G, *g_bound, *half_length, *radius, *VH, *NH, *OH, *EH, *excess;
    const int64_t *g_start, *g_kind, *v_start, *f_start, *e_start;
    const int64_t* kinds;
    const double *R_WO, *p_WO, *dims, *corners, *normals, *edges;
    const int64_t *n_corners, *n_normals, *n_edges;
};

// values (n, K) in place (penetration.py correct_clearances).
inline void correct_clearances(const Cores& C) {
    const int64_t n = C.n, K = C.K, G = C.G;
    std::vector<double> VO(3 * std::max<int64_t>(C.Vc, 2)), NO(3 * std::max<int64_t>(C.Fn, 1)),
        EO(3 * std::max<int64_t>(C.Ee, 1)), R_WG(9 * std::max<int64_t>(G, 1)), p_WG(3 * std::max<int64_t>(G, 1)),
        row(12 * std::max<int64_t>(G, 1));
    Packed s{};  // the obstacles as point_distance reads them (a mesh's pieces, clouds)
    s.K = K, s.kinds = C.kinds, s.R_WO = C.R_WO, s.p_WO = C.p_WO, s.dims = C.dims;
    auto centre = [&](int64_t g, const double* c, double* x) {
        const double* R = R_WG.data() + 9 * g;
        const double* p = p_WG.data() + 3 * g;
        for (int i = 0; i < 3; ++i) x[i] = p[i] + R[3 * i] * c[0] + R[3 * i + 1] * c[1] + R[3 * i + 2] * c[2];
    };
    for (int64_t r = 0; r < n; ++r) {
        for (int64_t j = 0; j < 4 * G; ++j)  // this configuration's points (4 G, 3), contiguous
            for (int i = 0; i < 3; ++i) row[3 * j + i] = C.points_W[r * C.ps[0] + j * C.ps[1] + i * C.ps[2]];
        const double* pts = row.data();
        for (int64_t g = 0; g < G; ++g)
            for (int i = 0; i < 3; ++i) {
                p_WG[3 * g + i] = pts[12 * g + i];
                for (int c = 0; c < 3; ++c) R_WG[9 * g + 3 * i + c] = pts[12 * g + 3 * (1 + c) + i] - pts[12 * g + i];
            }
        for (int64_t k = 0; k < K; ++k) {
            double& value = C.values[r * K + k];
            if (!(value < 0.0)) continue;
            const int64_t kind = C.kinds[k];
            if (kind > CAPSULE) {  // a convex piece or a cloud: the depth bound of the module docstring
                const double r_O = kind == 4 ? C.dims[3 * k + 2] : C.dims[3 * (int64_t)C.dims[3 * k]];
                double best = INF;
                for (int64_t g = 0; g < G; ++g) {
                    double s_g = INF, x[3];
                    for (int64_t i = C.g_start[g]; i < C.g_start[g + 1]; ++i) {
                        centre(g, C.c_G + 3 * i, x);
                        s_g = std::min(s_g, point_distance(s, k, x[0], x[1], x[2]) - C.radii[i]);
                    }
                    if (s_g < 0.0) best = std::min(best, std::min(s_g, -2.0 * (C.g_bound[g] + r_O)));
                }
                value = best;
                continue;
            }
            const double *d = C.dims + 3 * k, *R = C.R_WO + 9 * k, *p = C.p_WO + 3 * k;
            const Rows ck{C.corners + 3 * C.Vc * k, C.n_corners[k]}, nk{C.normals + 3 * C.Fn * k, C.n_normals[k]},
                ek{C.edges + 3 * C.Ee * k, C.n_edges[k]};
            double best = INF;
            for (int64_t g = 0; g < G; ++g) {
                const double* pg = p_WG.data() + 3 * g;
                if (sdf_at(kind, d, R, p, pg[0], pg[1], pg[2]) >= C.g_bound[g]) continue;
                double s_g = INF, x[3];
                for (int64_t i = C.g_start[g]; i < C.g_start[g + 1]; ++i) {
                    centre(g, C.c_G + 3 * i, x);
                    s_g = std::min(s_g, sdf_at(kind, d, R, p, x[0], x[1], x[2]) - C.radii[i]);
                }
                if (!(s_g < 0.0)) continue;
                double v_g;
                if (C.g_kind[g] == 0) {  // SEGMENT (drake_mh.geometry.spheres)
                    v_g = segment_bound(kind, d, R, p, pts + 12 * g, C.half_length[g], C.radius[g], ck, nk, ek);
                } else {
                    const int64_t f0 = C.f_start[g];
                    v_g = polytope_bound(kind, d, R, p, R_WG.data() + 9 * g, pg,
                                         Rows{C.VH + 3 * C.v_start[g], C.v_start[g + 1] - C.v_start[g]},
                                         Rows{C.NH + 3 * f0, C.f_start[g + 1] - f0}, C.OH + f0,
                                         Rows{C.EH + 3 * C.e_start[g], C.e_start[g + 1] - C.e_start[g]}, C.excess[g],
                                         ck, nk, ek, s_g, VO.data(), NO.data(), EO.data());
                }
                best = std::min(best, std::min(s_g, v_g));
            }
            value = best;
        }
    }
}

}  // namespace penetration
}  // namespace dmh

#pragma GCC pop_options
