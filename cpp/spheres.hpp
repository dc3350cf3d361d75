// The sphere model against the obstacles' closed forms, and self-collision sphere pairs: the
// per-lane (scalar) tests of drake_mh/scene/kernels/collision.py and pairs.py, in the same
// order with the same operations. Frames are read from R (F, 3, 3, L), p (F, 3, L) at lane b
// (L = 1: one configuration's R (F, 3, 3), p (F, 3)).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

#include "packed.hpp"
#include "pieces.hpp"

namespace dmh {

constexpr int64_t SPHERE = 0, BOX = 1, CYLINDER = 2, CAPSULE = 3;
constexpr double INF = std::numeric_limits<double>::infinity();

// World position of offset o (3,) fixed in moving frame a (-1: the world), lane b.
inline void lane_point(int64_t a, const double* o, const double* R, const double* p, int64_t L, int64_t b,
                       double& x, double& y, double& z) {
    const double o0 = o[0], o1 = o[1], o2 = o[2];
    if (a < 0) {
        x = o0, y = o1, z = o2;
        return;
    }
    const double* Ra = R + a * 9 * L + b;
    const double* pa = p + a * 3 * L + b;
    x = pa[0] + Ra[0] * o0 + Ra[L] * o1 + Ra[2 * L] * o2;
    y = pa[L] + Ra[3 * L] * o0 + Ra[4 * L] * o1 + Ra[5 * L] * o2;
    z = pa[2 * L] + Ra[6 * L] * o0 + Ra[7 * L] * o1 + Ra[8 * L] * o2;
}

// Whether point (x, y, z) is at least reach from obstacle k (squared distances; a mesh piece
// and a cloud: pieces.hpp).
// Point (x, y, z) relative to obstacle k's origin (dx, dy, dz), and in its frame (rotated: u, v, w).
struct Relative {
    const double* d;  // the obstacle's dims (3,)
    double dx, dy, dz;
    void rotated(const Packed& s, int64_t k, double& u, double& v, double& w) const {
        const double* Rw = s.R_WO + 9 * k;
        u = Rw[0] * dx + Rw[3] * dy + Rw[6] * dz;
        v = Rw[1] * dx + Rw[4] * dy + Rw[7] * dz;
        w = Rw[2] * dx + Rw[5] * dy + Rw[8] * dz;
    }
};
inline Relative relative(const Packed& s, int64_t k, double x, double y, double z) {
    const double* pw = s.p_WO + 3 * k;
    return Relative{s.dims + 3 * k, x - pw[0], y - pw[1], z - pw[2]};
}

inline bool point_free(const Packed& s, int64_t k, double reach, double x, double y, double z) {
    const int64_t kind = s.kinds[k];
    const Relative r = relative(s, k, x, y, z);
    const double *d = r.d, d0 = d[0], dx = r.dx, dy = r.dy, dz = r.dz;
    if (kind == SPHERE) return dx * dx + dy * dy + dz * dz >= (reach + d0) * (reach + d0);
    if (kind == CONVEX) return convex_free(s, k, dx, dy, dz, reach);
    if (kind == CLOUD) return cloud_free(s, k, x, y, z, reach + cloud_radius(s, k));
    double u, v, w;
    r.rotated(s, k, u, v, w);
    if (kind == BOX) {
        const double ox = smax(std::fabs(u) - d0, 0.0), oy = smax(std::fabs(v) - d[1], 0.0),
                     oz = smax(std::fabs(w) - d[2], 0.0);
        return ox * ox + oy * oy + oz * oz >= reach * reach;
    }
    if (kind == CYLINDER) {
        const double orr = smax(std::sqrt(u * u + v * v) - d0, 0.0), oa = smax(std::fabs(w) - d[1], 0.0);
        return orr * orr + oa * oa >= reach * reach;
    }
    w = w - smin(smax(w, -d[1]), d[1]);  // CAPSULE
    return u * u + v * v + w * w >= (reach + d0) * (reach + d0);
}

// Distance [m] of point (x, y, z) outside obstacle k, 0 or less inside (collision.py
// point_distance: the value point_free compares with its reach, with a square root).
inline double point_distance(const Packed& s, int64_t k, double x, double y, double z) {
    const int64_t kind = s.kinds[k];
    const Relative r = relative(s, k, x, y, z);
    const double *d = r.d, d0 = d[0], dx = r.dx, dy = r.dy, dz = r.dz;
    if (kind == SPHERE) return std::sqrt(dx * dx + dy * dy + dz * dz) - d0;
    if (kind == CONVEX) return convex_value(s, k, dx, dy, dz);
    if (kind == CLOUD) return std::sqrt(cloud_nearest2(s, k, x, y, z, INF)) - cloud_radius(s, k);
    double u, v, w;
    r.rotated(s, k, u, v, w);
    if (kind == BOX) {
        const double ox = smax(std::fabs(u) - d0, 0.0), oy = smax(std::fabs(v) - d[1], 0.0),
                     oz = smax(std::fabs(w) - d[2], 0.0);
        return std::sqrt(ox * ox + oy * oy + oz * oz);
    }
    if (kind == CYLINDER) {
        const double orr = smax(std::sqrt(u * u + v * v) - d0, 0.0), oa = smax(std::fabs(w) - d[1], 0.0);
        return std::sqrt(orr * orr + oa * oa);
    }
    w = w - smin(smax(w, -d[1]), d[1]);  // CAPSULE
    return std::sqrt(u * u + v * v + w * w) - d0;
}

// Whether the W points (x, y, z) are at least reach from obstacle k (as _obstacle_free); a mesh
// piece or a cloud is tested only in the lanes set in alive (the others read free).
inline vi obstacle_free_v(const Packed& s, int64_t k, double reach, vd x, vd y, vd z, vi alive) {
    const int64_t kind = s.kinds[k];
    const double* pw = s.p_WO + 3 * k;
    const double* Rw = s.R_WO + 9 * k;
    const double* d = s.dims + 3 * k;
    const vd dx = x - pw[0], dy = y - pw[1], dz = z - pw[2];
    if (kind == SPHERE) {
        const double lim = (reach + d[0]) * (reach + d[0]);
        return dx * dx + dy * dy + dz * dz >= lim;
    }
    if (kind == CLOUD) {  // the grid's lower bounds of every lane first (their loads overlap), then the rest
        const double r = reach + cloud_radius(s, k);
        double lower[W];
        for (int i = 0; i < W; ++i) lower[i] = cloud_lower(s, k, x[i], y[i], z[i]);
        vi free;
        for (int i = 0; i < W; ++i) free[i] = !alive[i] || lower[i] >= r ? -1 : 0;
        return free;
    }
    if (kind == CONVEX) {  // one lane at a time (the scalar tests)
        vi free;
        for (int i = 0; i < W; ++i) free[i] = !alive[i] || point_free(s, k, reach, x[i], y[i], z[i]) ? -1 : 0;
        return free;
    }
    const vd u = Rw[0] * dx + Rw[3] * dy + Rw[6] * dz;
    const vd v = Rw[1] * dx + Rw[4] * dy + Rw[7] * dz;
    vd w = Rw[2] * dx + Rw[5] * dy + Rw[8] * dz;
    const vd zero = splat(0.0);
    if (kind == BOX) {
        const vd ox = vmax(vabs(u) - d[0], zero), oy = vmax(vabs(v) - d[1], zero), oz = vmax(vabs(w) - d[2], zero);
        return ox * ox + oy * oy + oz * oz >= reach * reach;
    }
    if (kind == CYLINDER) {
        const vd orr = vmax(vsqrt(u * u + v * v) - d[0], zero), oa = vmax(vabs(w) - d[1], zero);
        return orr * orr + oa * oa >= reach * reach;
    }
    w = w - vmin(vmax(w, splat(-d[1])), splat(d[1]));  // CAPSULE
    const double lim = (reach + d[0]) * (reach + d[0]);
    return u * u + v * v + w * w >= lim;
}

// Centres of offset o fixed in frame a over nv vectors of lanes (collision.py _centre_block).
inline void centres_v(int64_t a, const double* o, const double* R, const double* p, int64_t L, int64_t nv,
                      double* cx, double* cy, double* cz) {
    const double o0 = o[0], o1 = o[1], o2 = o[2];
    for (int64_t v = 0; v < nv; ++v) {
        const int64_t b = v * W;
        if (a < 0) {
            store(cx + b, splat(o0)), store(cy + b, splat(o1)), store(cz + b, splat(o2));
            continue;
        }
        const double* Ra = R + a * 9 * L + b;
        const double* pa = p + a * 3 * L + b;
        store(cx + b, load(pa) + load(Ra) * o0 + load(Ra + L) * o1 + load(Ra + 2 * L) * o2);
        store(cy + b, load(pa + L) + load(Ra + 3 * L) * o0 + load(Ra + 4 * L) * o1 + load(Ra + 5 * L) * o2);
        store(cz + b, load(pa + 2 * L) + load(Ra + 6 * L) * o0 + load(Ra + 7 * L) * o1 + load(Ra + 8 * L) * o2);
    }
}

// Whether, in some lane set in mask (nv vectors), link g's bounding sphere (centres gx, gy, gz)
// is closer than clearance to obstacle k's bounding sphere.
inline bool bounding_close(const Packed& s, int64_t g, int64_t k, double clearance, const double* gx,
                           const double* gy, const double* gz, int64_t nv, const vi* mask) {
    double lim = clearance + s.g_radius[g] + s.o_radius[k];
    lim *= lim;
    const double px = s.p_WO[3 * k], py = s.p_WO[3 * k + 1], pz = s.p_WO[3 * k + 2];
    vi close{};
    for (int64_t v = 0; v < nv; ++v) {
        const vd dx = load(gx + v * W) - px, dy = load(gy + v * W) - py, dz = load(gz + v * W) - pz;
        close |= (dx * dx + dy * dy + dz * dz < lim) & mask[v];
    }
    return any(close);
}

// Spheres s0 .. s1-1 (frame a) of lane b all at least clearance from obstacle k.
inline bool range_free(const Packed& s, int64_t b, int64_t a, int64_t s0, int64_t s1, double clearance,
                       const double* R, const double* p, int64_t L, int64_t k) {
    if (s.kinds[k] == CLOUD) {  // eight spheres at a time: the grid's lower bounds first (their loads overlap)
        const double rho = cloud_radius(s, k);
        for (int64_t i0 = s0; i0 < s1; i0 += 8) {
            const int64_t n = std::min<int64_t>(8, s1 - i0);
            double cx[8], cy[8], cz[8], lower[8], upper[8], margin[8];
            int64_t open[8], m = 0;
            for (int64_t j = 0; j < n; ++j) {
                lane_point(a, s.s_offset + 3 * (i0 + j), R, p, L, b, cx[j], cy[j], cz[j]);
                cloud_bounds(s, k, cx[j], cy[j], cz[j], lower[j], upper[j]);
            }
            for (int64_t j = 0; j < n; ++j) {  // the undecided spheres, the deepest inside its lower bound first
                const double reach = clearance + s.s_radius[i0 + j] + rho;
                if (lower[j] >= reach) continue;
                if (upper[j] < reach) return false;
                margin[j] = lower[j] - reach;
                int64_t at = m++;
                for (; at > 0 && margin[open[at - 1]] > margin[j]; --at) open[at] = open[at - 1];
                open[at] = j;
            }
            for (int64_t u = 0; u < m; ++u) {
                const int64_t j = open[u];
                if (!cloud_exact_free(s, k, cx[j], cy[j], cz[j], clearance + s.s_radius[i0 + j] + rho)) return false;
            }
        }
        return true;
    }
    for (int64_t i = s0; i < s1; ++i) {
        double x, y, z;
        lane_point(a, s.s_offset + 3 * i, R, p, L, b, x, y, z);
        if (!point_free(s, k, clearance + s.s_radius[i], x, y, z)) return false;
    }
    return true;
}

// The spheres of groups u0 .. u1-1 (frame a) of lane b all at least clearance from obstacle
// k, a group whose bounding sphere keeps the clearance passed whole.
__attribute__((noinline)) inline bool groups_free(const Packed& s, int64_t b, int64_t a, int64_t u0, int64_t u1,
                                                  double clearance, const double* R, const double* p, int64_t L,
                                                  int64_t k) {
    for (int64_t u = u0; u < u1; ++u) {
        double x, y, z;
        lane_point(a, s.u_offset + 3 * u, R, p, L, b, x, y, z);
        const bool bound_free = s.kinds[k] == CLOUD ? cloud_lower(s, k, x, y, z) >= clearance + s.u_radius[u] + cloud_radius(s, k)
                                                    : point_free(s, k, clearance + s.u_radius[u], x, y, z);
        if (!bound_free &&
            !range_free(s, b, a, s.u_start[u], s.u_start[u + 1], clearance, R, p, L, k))
            return false;
    }
    return true;
}

// A lower bound of pair i's clearance at the configuration whose coordinate j is q[j * qs],
// from its floor table, or -inf without one.
inline double pair_floor(const Packed& s, int64_t i, const double* q, int64_t qs) {
    const int64_t* meta = s.t_meta + 6 * i;
    const double* grid = s.t_grid + GRID_COLUMNS * i;
    const int64_t dims = meta[0];
    if (dims == 0) return -INF;
    const int64_t n1 = meta[3];
    const double x = (q[meta[1] * qs] - grid[0]) * grid[1];
    if (!(x >= 0.0 && x <= (double)n1)) return -INF;
    int64_t cell = std::min((int64_t)x, n1 - 1);
    if (dims == 2) {
        const int64_t n2 = meta[4];
        const double y = (q[meta[2] * qs] - grid[2]) * grid[3];
        if (!(y >= 0.0 && y <= (double)n2)) return -INF;
        cell = cell * n2 + std::min((int64_t)y, n2 - 1);
    }
    return s.t_vals[meta[5] + cell];
}

// A lower bound of pair i's clearance on the whole straight motion qa -> qb (nq,) from its floor
// table: the smallest floor of the cells the motion's projection on the table's joints passes
// through (a grid walk, Amanatides and Woo 1987), or -inf without a table or with an end outside
// the table's joint limits (pairs.py segment_floor, the same walk).
inline double segment_floor(const Packed& s, int64_t i, const double* qa, const double* qb) {
    const int64_t* meta = s.t_meta + 6 * i;
    const double* grid = s.t_grid + GRID_COLUMNS * i;
    const int64_t dims = meta[0];
    if (dims == 0) return -INF;
    const int64_t j1 = meta[1], j2 = meta[2], n1 = meta[3], n2 = meta[4];
    const double* vals = s.t_vals + meta[5];
    const double x0 = (qa[j1] - grid[0]) * grid[1], x1 = (qb[j1] - grid[0]) * grid[1];
    if (!(x0 >= 0.0 && x0 <= (double)n1 && x1 >= 0.0 && x1 <= (double)n1)) return -INF;
    int64_t cx = std::min((int64_t)x0, n1 - 1);
    const int64_t ex = std::min((int64_t)x1, n1 - 1);
    double best = INF;
    if (dims == 1) {
        for (int64_t c = std::min(cx, ex); c <= std::max(cx, ex); ++c) best = smin(best, vals[c]);
        return best;
    }
    const double y0 = (qa[j2] - grid[2]) * grid[3], y1 = (qb[j2] - grid[2]) * grid[3];
    if (!(y0 >= 0.0 && y0 <= (double)n2 && y1 >= 0.0 && y1 <= (double)n2)) return -INF;
    int64_t cy = std::min((int64_t)y0, n2 - 1);
    const int64_t ey = std::min((int64_t)y1, n2 - 1);
    const double dx = x1 - x0, dy = y1 - y0;
    const int64_t sx = ex > cx ? 1 : -1, sy = ey > cy ? 1 : -1;
    // the motion's parameter where it leaves the current cell along x / along y, and per cell
    double tx = dx != 0.0 ? (sx > 0 ? ((double)cx + 1.0 - x0) / dx : (x0 - (double)cx) / -dx) : INF;
    double ty = dy != 0.0 ? (sy > 0 ? ((double)cy + 1.0 - y0) / dy : (y0 - (double)cy) / -dy) : INF;
    const double ux = dx != 0.0 ? std::fabs(1.0 / dx) : INF, uy = dy != 0.0 ? std::fabs(1.0 / dy) : INF;
    const int64_t steps = std::abs(ex - cx) + std::abs(ey - cy) + 1;
    for (int64_t step = 0; step < steps; ++step) {  // a staircase from the first cell to the last
        best = smin(best, vals[cx * n2 + cy]);
        if (cx != ex && (cy == ey || tx < ty)) {
            cx += sx;
            tx += ux;
        } else if (cy != ey) {
            cy += sy;
            ty += uy;
        }
    }
    return best;
}

// A lower bound of links ga and gb's sphere-pair clearance in lane b: their bounding capsules'
// distance less 1 um (Ericson, Real-Time Collision Detection 5.1.9).
inline double capsule_gap(const Packed& s, int64_t b, int64_t ga, int64_t gb, const double* R, const double* p,
                          int64_t L) {
    const double* ca = s.g_capsule + 7 * ga;
    const double* cb = s.g_capsule + 7 * gb;
    double ax0, ay0, az0, ax1, ay1, az1, bx0, by0, bz0, bx1, by1, bz1;
    lane_point(s.g_anchor[ga], ca, R, p, L, b, ax0, ay0, az0);
    lane_point(s.g_anchor[ga], ca + 3, R, p, L, b, ax1, ay1, az1);
    lane_point(s.g_anchor[gb], cb, R, p, L, b, bx0, by0, bz0);
    lane_point(s.g_anchor[gb], cb + 3, R, p, L, b, bx1, by1, bz1);
    const double ux = ax1 - ax0, uy = ay1 - ay0, uz = az1 - az0;
    const double vx = bx1 - bx0, vy = by1 - by0, vz = bz1 - bz0;
    const double wx = ax0 - bx0, wy = ay0 - by0, wz = az0 - bz0;
    const double a = ux * ux + uy * uy + uz * uz;
    const double e = vx * vx + vy * vy + vz * vz;
    const double f = vx * wx + vy * wy + vz * wz;
    const double eps = 1e-18;
    double t_s, t_t;
    auto clamp01 = [](double x) { return smin(smax(x, 0.0), 1.0); };
    if (a <= eps && e <= eps) {
        t_s = 0.0, t_t = 0.0;
    } else if (a <= eps) {
        t_s = 0.0, t_t = clamp01(f / e);
    } else {
        const double c = ux * wx + uy * wy + uz * wz;
        if (e <= eps) {
            t_s = clamp01(-c / a), t_t = 0.0;
        } else {
            const double bb = ux * vx + uy * vy + uz * vz;
            const double denom = a * e - bb * bb;
            t_s = denom > 0.0 ? clamp01((bb * f - c * e) / denom) : 0.0;
            t_t = (bb * t_s + f) / e;
            if (t_t < 0.0) {
                t_s = clamp01(-c / a), t_t = 0.0;
            } else if (t_t > 1.0) {
                t_s = clamp01((bb - c) / a), t_t = 1.0;
            }
        }
    }
    const double dx = wx + ux * t_s - vx * t_t;
    const double dy = wy + uy * t_s - vy * t_t;
    const double dz = wz + uz * t_s - vz * t_t;
    return std::sqrt(dx * dx + dy * dy + dz * dz) - ca[6] - cb[6] - 1e-6;
}

// Append to buf[n:] (rows x, y, z, r) the spheres s0 .. s1-1 (frame a, lane b) closer than
// bound to the sphere (c, reach); low: with lower, the smallest value of a sphere left out.
inline int64_t near_spheres(const Packed& s, int64_t b, int64_t a, int64_t s0, int64_t s1, const double* R,
                            const double* p, int64_t L, double cx, double cy, double cz, double reach, double bound,
                            bool lower, double* buf, int64_t n, double& low) {
    low = INF;
    for (int64_t i = s0; i < s1; ++i) {
        double x, y, z;
        lane_point(a, s.s_offset + 3 * i, R, p, L, b, x, y, z);
        const double lim = bound + s.s_radius[i] + reach;
        const double dx = x - cx, dy = y - cy, dz = z - cz;
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (lim > 0.0 && d2 < lim * lim) {
            double* r = buf + 4 * n;
            r[0] = x, r[1] = y, r[2] = z, r[3] = s.s_radius[i];
            ++n;
        } else if (lower) {
            low = smin(low, std::sqrt(d2) - s.s_radius[i] - reach);
        }
    }
    return n;
}

// near_spheres over the spheres of groups u0 .. u1-1, tested in frame a (pairs.py _near_groups).
inline int64_t near_groups(const Packed& s, int64_t b, int64_t a, int64_t u0, int64_t u1, const double* R,
                           const double* p, int64_t L, double cx, double cy, double cz, double reach, double bound,
                           bool lower, double* buf, int64_t n, double& low) {
    double lx, ly, lz;
    const double* Ra = R + a * 9 * L + b;
    const double* pa = p + a * 3 * L + b;
    if (a >= 0) {
        const double dx = cx - pa[0], dy = cy - pa[L], dz = cz - pa[2 * L];
        lx = Ra[0] * dx + Ra[3 * L] * dy + Ra[6 * L] * dz;
        ly = Ra[L] * dx + Ra[4 * L] * dy + Ra[7 * L] * dz;
        lz = Ra[2 * L] * dx + Ra[5 * L] * dy + Ra[8 * L] * dz;
    } else {
        lx = cx, ly = cy, lz = cz;
    }
    low = INF;
    for (int64_t u = u0; u < u1; ++u) {
        const double* uo = s.u_offset + 3 * u;
        double dx = uo[0] - lx, dy = uo[1] - ly, dz = uo[2] - lz;
        double d2 = dx * dx + dy * dy + dz * dz;
        double lim = bound + s.u_radius[u] + reach;
        if (!(lim > 0.0 && d2 < lim * lim)) {
            if (lower) low = smin(low, std::sqrt(d2) - s.u_radius[u] - reach);
            continue;
        }
        for (int64_t i = s.u_start[u]; i < s.u_start[u + 1]; ++i) {
            const double ox = s.s_offset[3 * i], oy = s.s_offset[3 * i + 1], oz = s.s_offset[3 * i + 2];
            dx = ox - lx, dy = oy - ly, dz = oz - lz;
            d2 = dx * dx + dy * dy + dz * dz;
            lim = bound + s.s_radius[i] + reach;
            if (lim > 0.0 && d2 < lim * lim) {
                double* r = buf + 4 * n;
                if (a >= 0) {
                    r[0] = pa[0] + Ra[0] * ox + Ra[L] * oy + Ra[2 * L] * oz;
                    r[1] = pa[L] + Ra[3 * L] * ox + Ra[4 * L] * oy + Ra[5 * L] * oz;
                    r[2] = pa[2 * L] + Ra[6 * L] * ox + Ra[7 * L] * oy + Ra[8 * L] * oz;
                } else {
                    r[0] = ox, r[1] = oy, r[2] = oz;
                }
                r[3] = s.s_radius[i];
                ++n;
            } else if (lower) {
                low = smin(low, std::sqrt(d2) - s.s_radius[i] - reach);
            }
        }
    }
    return n;
}

constexpr int64_t PAIR_CHUNK = 8;  // spheres per run in pair_clearance's pruning

// pair_clearance's runs' bounding spheres, one array per thread (no allocation once grown).
inline std::vector<double>& pair_runs_scratch() {
    thread_local std::vector<double> runs;
    return runs;
}

// The clearance of links ga and gb in lane b where it is below bound (pairs.py pair_clearance):
// the smallest |c_s - c_t| - r_s - r_t there, else bound (with lower: a lower bound >= bound);
// returns at once below stop. (ca, cb): the links' bounding-sphere centres; buf (S, 4) scratch.
__attribute__((noinline)) inline double pair_clearance(const Packed& s, int64_t b, int64_t ga, int64_t gb,
                                                       double bound, double stop, bool lower, double cax,
                                                       double cay, double caz, double cbx, double cby, double cbz,
                                                       const double* R, const double* p, int64_t L, double* buf) {
    const bool grouped = bound < INF;
    double low_a, low_b;
    int64_t na, n;
    if (grouped)
        na = near_groups(s, b, s.g_anchor[ga], s.g_ustart[ga], s.g_ustart[ga + 1], R, p, L, cbx, cby, cbz,
                         s.g_radius[gb], bound, lower, buf, 0, low_a);
    else
        na = near_spheres(s, b, s.g_anchor[ga], s.g_start[ga], s.g_start[ga + 1], R, p, L, cbx, cby, cbz,
                          s.g_radius[gb], bound, lower, buf, 0, low_a);
    if (na == 0) return lower ? low_a : bound;
    if (grouped)
        n = near_groups(s, b, s.g_anchor[gb], s.g_ustart[gb], s.g_ustart[gb + 1], R, p, L, cax, cay, caz,
                        s.g_radius[ga], bound, lower, buf, na, low_b);
    else
        n = near_spheres(s, b, s.g_anchor[gb], s.g_start[gb], s.g_start[gb + 1], R, p, L, cax, cay, caz,
                         s.g_radius[ga], bound, lower, buf, na, low_b);
    double best = lower ? smin(low_a, low_b) : bound;
    // the smallest value over spheres i0 .. i1-1 of a and j0 .. j1-1 of b (in buf) below best
    auto block = [&](int64_t i0, int64_t i1, int64_t j0, int64_t j1) {
        for (int64_t i = i0; i < i1; ++i) {
            const double x = buf[4 * i], y = buf[4 * i + 1], z = buf[4 * i + 2], r = buf[4 * i + 3];
            for (int64_t j = j0; j < j1; ++j) {
                const double* t = buf + 4 * j;
                const double dx = x - t[0], dy = y - t[1], dz = z - t[2];
                const double d2 = dx * dx + dy * dy + dz * dz;
                const double lim = best + r + t[3];
                if (lim > 0.0 && d2 >= lim * lim) continue;
                const double value = std::sqrt(d2) - r - t[3];
                if (value < best) {
                    best = value;
                    if (best < stop) return true;
                }
            }
        }
        return false;
    };
    const int64_t nb = n - na;
    if (na * nb <= PAIR_CHUNK * PAIR_CHUNK * 4) {
        block(0, na, na, n);
        return best;
    }
    // Many sphere pairs: b's spheres in runs of PAIR_CHUNK (neighbours in their link's order),
    // each bounded by a sphere; a sphere of a skips the runs whose bound keeps all their spheres
    // above the smallest value so far (the same smallest value, fewer distances).
    const int64_t kb = (nb + PAIR_CHUNK - 1) / PAIR_CHUNK;
    std::vector<double>& run_spheres = pair_runs_scratch();
    run_spheres.resize((size_t)(4 * kb));
    double* runs = run_spheres.data();  // (kb, 4): centre and radius of each run
    for (int64_t k = 0; k < kb; ++k) {
        const int64_t j0 = na + k * PAIR_CHUNK, j1 = std::min(j0 + PAIR_CHUNK, n);
        double lo[3] = {INF, INF, INF}, hi[3] = {-INF, -INF, -INF};
        for (int64_t j = j0; j < j1; ++j)
            for (int u = 0; u < 3; ++u) lo[u] = smin(lo[u], buf[4 * j + u]), hi[u] = smax(hi[u], buf[4 * j + u]);
        double* c = runs + 4 * k;
        for (int u = 0; u < 3; ++u) c[u] = 0.5 * (lo[u] + hi[u]);
        double radius = 0.0;
        for (int64_t j = j0; j < j1; ++j) {
            const double dx = buf[4 * j] - c[0], dy = buf[4 * j + 1] - c[1], dz = buf[4 * j + 2] - c[2];
            radius = smax(radius, std::sqrt(dx * dx + dy * dy + dz * dz) + buf[4 * j + 3]);
        }
        c[3] = radius * (1.0 + 1e-12) + 1e-12;  // rounding: the run's sphere holds its spheres
    }
    for (int64_t i = 0; i < na; ++i) {
        const double x = buf[4 * i], y = buf[4 * i + 1], z = buf[4 * i + 2], r = buf[4 * i + 3];
        for (int64_t k = 0; k < kb; ++k) {
            const double* c = runs + 4 * k;
            const double dx = x - c[0], dy = y - c[1], dz = z - c[2];
            const double lim = best + r + c[3];
            if (lim > 0.0 && dx * dx + dy * dy + dz * dz >= lim * lim * (1.0 + 1e-12)) continue;
            const int64_t j0 = na + k * PAIR_CHUNK;
            if (block(i, i + 1, j0, std::min(j0 + PAIR_CHUNK, n))) return best;
        }
    }
    return best;
}

}  // namespace dmh
