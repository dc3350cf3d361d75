// Point-cloud obstacles: their shape-table entry (a grid of distance bounds and a bounding-box
// tree of the points) and the queries on it. drake_mh/scene/kernels/cloud.py holds the same
// build and the same queries in numba, and describes the layout; the two builds write the same
// table (the same operations on the same values).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "packed.hpp"

namespace dmh {

constexpr int64_t CLOUD = 5;
constexpr int64_t CLOUD_LEAF = 16;       // cloud.py LEAF: a range of at most this many points is a leaf
constexpr int64_t CLOUD_COUNT_BITS = 6;  // a leaf's code: -(1 + start * 64 + count)
constexpr int CLOUD_MORTON_BITS = 8;     // cloud.py MORTON_BITS: per axis
constexpr int CLOUD_STACK = 3 * CLOUD_MORTON_BITS + 66;  // deeper than any path of the tree
constexpr int64_t CLOUD_NODE_ROWS = 5;      // a node: its children's boxes (4 rows), their codes
constexpr int64_t CLOUD_CELLS_PER_ROW = 12;  // cloud.py: a cell's value is a uint16, twelve to a row of three doubles
constexpr double CLOUD_STEPS = 256.0;        // cloud.py STEPS: a cell's value counts steps of h / 256
constexpr double CLOUD_SATURATED = 65535.0;  // a value at least this many steps
const double CLOUD_UPPER = 2.0 * std::sqrt(3.0);  // [cells] a cell's upper bound exceeds its lower by this

inline const double* cloud_row(const double* dims, int64_t row) { return dims + 3 * row; }

// Bounds (lower, upper) [m] of the distance from (x, y, z) (in W) to the nearest point of cloud
// k, from its grid (cloud.py cloud_bounds): inside the grid, the cell's value u steps of h / 256
// below L (no point of the cell is nearer than L to a point of the cloud), u h / 256, and
// (u + 1) h / 256 + 2 sqrt(3) h (inf where u saturated); outside, from the cell of the point's
// projection y onto the grid's box: d(x)^2 >= |x - y|^2 + L(y)^2 (every point of the cloud lies
// in the box, on the far side of y) and d(x) <= |x - y| + L(y) + 2 sqrt(3) h.
inline void cloud_bounds(const Packed& s, int64_t k, double x, double y, double z, double& lower, double& upper) {
    const double* d = s.dims;
    const int64_t st = (int64_t)cloud_row(d, k)[0];
    const double* head = cloud_row(d, st);
    const double h = head[1];
    const double ox = head[3], oy = head[4], oz = head[5];
    const int64_t nx = (int64_t)head[6], ny = (int64_t)head[7], nz = (int64_t)head[8];
    const uint16_t* cells = reinterpret_cast<const uint16_t*>(cloud_row(d, st + 3));
    const double step = h / CLOUD_STEPS;
    const double fx = (x - ox) / h, fy = (y - oy) / h, fz = (z - oz) / h;
    if (fx >= 0.0 && fy >= 0.0 && fz >= 0.0 && fx < (double)nx && fy < (double)ny && fz < (double)nz) {
        const double u = (double)cells[((int64_t)fx * ny + (int64_t)fy) * nz + (int64_t)fz];
        lower = u * step;
        upper = u < CLOUD_SATURATED ? ((u + 1.0) * step + CLOUD_UPPER * h) * (1.0 + 1e-9) + 1e-9 : INFINITY;
        return;
    }
    const int64_t ix = fx < 0.0 ? 0 : fx >= (double)nx ? nx - 1 : (int64_t)fx;
    const int64_t iy = fy < 0.0 ? 0 : fy >= (double)ny ? ny - 1 : (int64_t)fy;
    const int64_t iz = fz < 0.0 ? 0 : fz >= (double)nz ? nz - 1 : (int64_t)fz;
    const double u = (double)cells[(ix * ny + iy) * nz + iz], L = u * step;
    const double gx = std::max(std::max(ox - x, 0.0), x - ox - (double)nx * h);
    const double gy = std::max(std::max(oy - y, 0.0), y - oy - (double)ny * h);
    const double gz = std::max(std::max(oz - z, 0.0), z - oz - (double)nz * h);
    const double out2 = gx * gx + gy * gy + gz * gz;
    lower = std::sqrt(out2 + L * L) * (1.0 - 1e-12);  // round-off: never above the distance
    upper = u < CLOUD_SATURATED ? (std::sqrt(out2) + (u + 1.0) * step + CLOUD_UPPER * h) * (1.0 + 1e-9) + 1e-9
                                : INFINITY;
}

// The lower bound of cloud_bounds alone (the same value).
inline double cloud_lower(const Packed& s, int64_t k, double x, double y, double z) {
    double lower, upper;
    cloud_bounds(s, k, x, y, z, lower, upper);
    return lower;
}

// Squared distance from (x, y, z) to the box b (lower corner b[0..2], upper b[3..5]).
inline double cloud_box2(const double* b, double x, double y, double z) {
    const double gx = std::max(std::max(b[0] - x, 0.0), x - b[3]);
    const double gy = std::max(std::max(b[1] - y, 0.0), y - b[4]);
    const double gz = std::max(std::max(b[2] - z, 0.0), z - b[5]);
    return gx * gx + gy * gy + gz * gz;
}

// The smaller of best and the smallest squared distance from (x, y, z) to the points of the tree
// whose points start at row first and nodes at row nodes, returning as soon as it is below stop
// (cloud.py tree_nearest2): depth first, the nearer child first, a child whose box is no nearer
// than the best so far skipped (also when it comes off the stack).
inline double cloud_tree_nearest2(const double* d, int64_t first, int64_t nodes, double x, double y, double z,
                                  double best, double stop) {
    int64_t code_stack[CLOUD_STACK];
    double box_stack[CLOUD_STACK];
    int sp = 0;
    int64_t c = 0;
    while (true) {
        if (c >= 0) {
            const double* n = cloud_row(d, nodes + CLOUD_NODE_ROWS * c);
            const int64_t ca = (int64_t)n[12], cb = (int64_t)n[13];
            // the children's rows on their way while this node's boxes are compared (the first
            // child's first row follows this node's, the second child's may be far)
            if (ca >= 0) __builtin_prefetch(cloud_row(d, nodes + CLOUD_NODE_ROWS * ca) + 8);
            if (cb >= 0) {
                __builtin_prefetch(cloud_row(d, nodes + CLOUD_NODE_ROWS * cb));
                __builtin_prefetch(cloud_row(d, nodes + CLOUD_NODE_ROWS * cb) + 8);
            }
            const double a = cloud_box2(n, x, y, z), b = cloud_box2(n + 6, x, y, z);
            const bool first = a <= b;  // the nearer child now, the other one on the stack
            const double near = first ? a : b, far = first ? b : a;
            if (near < best) {
                code_stack[sp] = first ? cb : ca;
                box_stack[sp] = far;
                sp += far < best;
                c = first ? ca : cb;
                continue;
            }
        } else {
            const int64_t v = -c - 1, j0 = v >> CLOUD_COUNT_BITS, j1 = j0 + (v & ((1 << CLOUD_COUNT_BITS) - 1));
            for (int64_t j = j0; j < j1; ++j) {
                const double* p = cloud_row(d, first + j);
                const double dx = x - p[0], dy = y - p[1], dz = z - p[2];
                best = std::min(best, dx * dx + dy * dy + dz * dz);
            }
            if (best < stop) return best;
        }
        while (true) {  // the deepest pending child still nearer than the best
            if (sp == 0) return best;
            --sp;
            if (box_stack[sp] < best) {
                c = code_stack[sp];
                break;
            }
        }
    }
}

// The first point row and the first node row of cloud k.
inline void cloud_rows(const Packed& s, int64_t k, int64_t& first, int64_t& nodes) {
    const int64_t st = (int64_t)cloud_row(s.dims, k)[0], N = (int64_t)cloud_row(s.dims, k)[1];
    first = st + (int64_t)cloud_row(s.dims, st)[2];
    nodes = first + N;
}

// The smallest squared distance [m^2] from (x, y, z) (in W) to a point of cloud k, or bound2 if
// none is nearer (cloud.py cloud_nearest2: the grid's bounds first, then the tree).
inline double cloud_nearest2(const Packed& s, int64_t k, double x, double y, double z, double bound2) {
    double lower, upper;
    cloud_bounds(s, k, x, y, z, lower, upper);
    if (lower * lower >= bound2) return bound2;
    int64_t first, nodes;
    cloud_rows(s, k, first, nodes);
    const double start = upper * upper < bound2 ? upper * upper : bound2;
    return cloud_tree_nearest2(s.dims, first, nodes, x, y, z, start, -1.0);
}

// The radius [m] of cloud k's balls.
inline double cloud_radius(const Packed& s, int64_t k) { return cloud_row(s.dims, (int64_t)cloud_row(s.dims, k)[0])[0]; }

// Whether every point of cloud k is at least reach [m] (> 0) from (x, y, z) (in W), by the tree
// alone (cloud_free without the grid's bounds: where they could not tell).
inline bool cloud_exact_free(const Packed& s, int64_t k, double x, double y, double z, double reach) {
    int64_t first, nodes;
    cloud_rows(s, k, first, nodes);
    const double lim = reach * reach;
    return cloud_tree_nearest2(s.dims, first, nodes, x, y, z, lim, lim) >= lim;
}

// Whether every point of cloud k is at least reach [m] (> 0) from (x, y, z) (in W): the grid's
// bounds first, the tree (stopping at the first point nearer) where they cannot tell. Not
// inlined: its callers' loops stay small.
__attribute__((noinline)) inline bool cloud_free(const Packed& s, int64_t k, double x, double y, double z,
                                                 double reach) {
    double lower, upper;
    cloud_bounds(s, k, x, y, z, lower, upper);
    if (lower >= reach) return true;
    if (upper < reach) return false;
    return cloud_exact_free(s, k, x, y, z, reach);
}

}  // namespace dmh
