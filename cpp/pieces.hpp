// The obstacle kinds whose data live in the shape table dims (D, 3): convex pieces of a mesh and
// point clouds. The boolean tests of drake_mh/scene/kernels/pieces.py (convex_free, cloud_free
// and what they call), in the same order with the same operations; the table's layout is
// described there.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "packed.hpp"

namespace dmh {

constexpr int64_t CONVEX = 4, CLOUD = 5;
constexpr int64_t LEAF = 8;  // ranges of at most this many points are scanned, not split
const double UPPER = 2.0 * std::sqrt(3.0);  // [cells] a cell's upper bound exceeds its lower by this

inline double cell_of(const double* dims, int64_t row, int64_t col) { return dims[3 * row + col]; }
// Value i of a run stored three to a row from row `row` (dims[row + i // 3, i % 3]).
inline double run_of(const double* dims, int64_t row, int64_t i) { return dims[3 * row + i]; }

// Whether some plane of convex piece k keeps the point (x, y, z) (relative to p_WO[k]) at least
// reach away; stops at the first.
inline bool convex_free(const Packed& s, int64_t k, double x, double y, double z, double reach) {
    const double* d = s.dims;
    const int64_t st = (int64_t)cell_of(d, k, 0), M = (int64_t)cell_of(d, k, 1);
    for (int64_t i = 0; i < M; ++i)
        if (cell_of(d, st + i, 0) * x + cell_of(d, st + i, 1) * y + cell_of(d, st + i, 2) * z -
                run_of(d, st + M, i) >= reach)
            return true;
    return false;
}

// max_i (n_i . (x, y, z) - h_i) of convex piece k, the point relative to p_WO[k]: a lower bound
// of its signed distance, exact inside (pieces.py convex_value).
inline double convex_value(const Packed& s, int64_t k, double x, double y, double z) {
    const double* d = s.dims;
    const int64_t st = (int64_t)cell_of(d, k, 0), M = (int64_t)cell_of(d, k, 1);
    double best = -std::numeric_limits<double>::infinity();
    for (int64_t i = 0; i < M; ++i)
        best = smax(best, cell_of(d, st + i, 0) * x + cell_of(d, st + i, 1) * y + cell_of(d, st + i, 2) * z -
                              run_of(d, st + M, i));
    return best;
}

// Squared distance from (x, y, z) to the bounding box of the range whose median is at mid (rows
// b0 + 2 mid: its lower corner, b0 + 2 mid + 1: its upper corner): pieces.py _box2.
inline double box2(const double* d, int64_t b0, int64_t mid, double x, double y, double z) {
    const double* lo = d + 3 * (b0 + 2 * mid);
    const double* hi = lo + 3;
    const double gx = smax(smax(lo[0] - x, 0.0), x - hi[0]);
    const double gy = smax(smax(lo[1] - y, 0.0), y - hi[1]);
    const double gz = smax(smax(lo[2] - z, 0.0), z - hi[2]);
    return gx * gx + gy * gy + gz * gz;
}

// The smaller of best and the smallest squared distance from (x, y, z) to the points of the
// implicit k-d tree at rows st .. st+N-1 (split axes from row a0, the ranges' bounding boxes from
// row b0), returning as soon as it is below stop: pieces.py _nearest2. Depth first, the side with
// the nearer box first (the point's side of the split plane where a half is a leaf); a range whose
// box is no nearer than the best so far is skipped whole, the side beyond the split plane only
// while the plane is nearer than the best (bit d of path: the side taken at depth d; of pending:
// its other side still to be tried).
inline double nearest2(const double* d, int64_t st, int64_t a0, int64_t b0, int64_t N, double x, double y, double z,
                       double best, double stop) {
    int64_t lo = 0, hi = N, depth = 0;
    uint64_t path = 0, pending = 0;
    while (true) {
        bool leaf = true;
        while (hi - lo > LEAF) {  // down to a leaf, the nearer side first
            const int64_t mid = (lo + hi) >> 1;
            if (box2(d, b0, mid, x, y, z) >= best) {  // nothing in this range is nearer
                leaf = false;
                break;
            }
            const double dx = x - cell_of(d, st + mid, 0), dy = y - cell_of(d, st + mid, 1),
                         dz = z - cell_of(d, st + mid, 2);
            best = smin(best, dx * dx + dy * dy + dz * dz);
            if (best < stop) return best;
            const int64_t axis = (int64_t)run_of(d, a0, mid);
            const double diff = axis == 0 ? dx : axis == 1 ? dy : dz;
            bool upper = diff >= 0.0;  // the side of the split plane the point is on
            if (mid - lo > LEAF && hi - mid - 1 > LEAF)  // two boxes: the nearer first
                upper = box2(d, b0, (mid + 1 + hi) >> 1, x, y, z) < box2(d, b0, (lo + mid) >> 1, x, y, z);
            if (upper) {
                lo = mid + 1;
                path |= uint64_t(1) << depth;
            } else {
                hi = mid;
            }
            pending |= uint64_t(1) << depth;
            ++depth;
        }
        if (leaf) {
            double other = best;  // two running minima: a shorter dependency chain, the same minimum
            int64_t j = lo;
            for (; j + 1 < hi; j += 2) {
                const double* a = d + 3 * (st + j);
                const double ax = x - a[0], ay = y - a[1], az = z - a[2];
                const double bx = x - a[3], by = y - a[4], bz = z - a[5];
                best = smin(best, ax * ax + ay * ay + az * az);
                other = smin(other, bx * bx + by * by + bz * bz);
            }
            if (j < hi) {
                const double dx = x - cell_of(d, st + j, 0), dy = y - cell_of(d, st + j, 1),
                             dz = z - cell_of(d, st + j, 2);
                best = smin(best, dx * dx + dy * dy + dz * dz);
            }
            best = smin(best, other);
            if (best < stop) return best;
        }
        while (true) {  // back to the deepest split whose other side can still hold a nearer point
            if (pending == 0) return best;
            int64_t dd = depth - 1;
            while (!((pending >> dd) & 1)) --dd;
            pending &= ~(uint64_t(1) << dd);
            lo = 0, hi = N;
            for (int64_t e = 0; e < dd; ++e) {
                const int64_t mid = (lo + hi) >> 1;
                if ((path >> e) & 1)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            const int64_t mid = (lo + hi) >> 1;
            const int64_t axis = (int64_t)run_of(d, a0, mid);
            const double diff = (axis == 0 ? x : axis == 1 ? y : z) - cell_of(d, st + mid, axis);
            const uint64_t far = 1 - ((path >> dd) & 1);  // the side not taken: beyond the plane or the point's own
            if (diff * diff < best || far == (diff >= 0.0 ? 1u : 0u)) {
                if (far)
                    lo = mid + 1;
                else
                    hi = mid;
                path = (path & ((uint64_t(1) << dd) - 1)) | (far << dd);
                depth = dd + 1;
                break;
            }
        }
    }
}

// Bounds (lower, upper) [m] of the distance from (x, y, z) (in W) to the nearest point of cloud
// k, from its grid (pieces.py _cloud_bounds).
inline void cloud_bounds(const Packed& s, int64_t k, double x, double y, double z, double& lower, double& upper) {
    const double* d = s.dims;
    const int64_t st = (int64_t)cell_of(d, k, 0);
    const double h = cell_of(d, st, 1);
    const double ox = cell_of(d, st + 1, 0), oy = cell_of(d, st + 1, 1), oz = cell_of(d, st + 1, 2);
    const int64_t nx = (int64_t)cell_of(d, st + 2, 0), ny = (int64_t)cell_of(d, st + 2, 1),
                  nz = (int64_t)cell_of(d, st + 2, 2);
    const double fx = (x - ox) / h, fy = (y - oy) / h, fz = (z - oz) / h;
    if (fx < 0.0 || fy < 0.0 || fz < 0.0 || fx >= (double)nx || fy >= (double)ny || fz >= (double)nz) {
        const double gx = smax(smax(ox - x, 0.0), x - ox - (double)nx * h);
        const double gy = smax(smax(oy - y, 0.0), y - oy - (double)ny * h);
        const double gz = smax(smax(oz - z, 0.0), z - oz - (double)nz * h);
        lower = std::sqrt(gx * gx + gy * gy + gz * gz);
        upper = std::numeric_limits<double>::infinity();
        return;
    }
    const int64_t c = ((int64_t)fx * ny + (int64_t)fy) * nz + (int64_t)fz;
    lower = run_of(d, st + 3, c);
    upper = (lower + UPPER * h) * (1.0 + 1e-9) + 1e-9;
}

// The smallest squared distance [m^2] from (x, y, z) (in W) to a point of cloud k, or bound2 if
// none is nearer (pieces.py cloud_nearest2: the grid's bounds first, then the k-d tree).
inline double cloud_nearest2(const Packed& s, int64_t k, double x, double y, double z, double bound2) {
    double lower, upper;
    cloud_bounds(s, k, x, y, z, lower, upper);
    if (lower * lower >= bound2) return bound2;
    const double* d = s.dims;
    const int64_t st = (int64_t)cell_of(d, k, 0), N = (int64_t)cell_of(d, k, 1);
    const int64_t first = st + (int64_t)cell_of(d, st, 2);
    const double start = upper * upper < bound2 ? upper * upper : bound2;
    return nearest2(d, first, first + N, first + N + (N + 2) / 3, N, x, y, z, start, -1.0);
}

// The radius [m] of cloud k's balls.
inline double cloud_radius(const Packed& s, int64_t k) { return cell_of(s.dims, (int64_t)cell_of(s.dims, k, 0), 0); }

// Whether every point of cloud k is at least reach [m] (> 0) from (x, y, z) (in W): the grid's
// bounds first, the k-d tree (stopping at the first point nearer, skipping the ranges whose boxes
// are not nearer) where they cannot tell. Not
// inlined: its callers' loops stay small (measured: 5-10 % faster checks on a cloud).
__attribute__((noinline)) inline bool cloud_free(const Packed& s, int64_t k, double x, double y, double z,
                                                 double reach) {
    double lower, upper;
    cloud_bounds(s, k, x, y, z, lower, upper);
    if (lower >= reach) return true;
    if (upper < reach) return false;
    const double* d = s.dims;
    const int64_t st = (int64_t)cell_of(d, k, 0), N = (int64_t)cell_of(d, k, 1);
    const int64_t first = st + (int64_t)cell_of(d, st, 2);
    const double lim = reach * reach;
    return nearest2(d, first, first + N, first + N + (N + 2) / 3, N, x, y, z, lim, lim) >= lim;
}

}  // namespace dmh
