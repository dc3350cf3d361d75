// The obstacle kinds whose data live in the shape table dims (D, 3): convex pieces of a mesh
// (drake_mh/scene/kernels/pieces.py convex_free, convex_value: the same operations in the same
// order; the table's layout is described there) and point clouds (cloud.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "cloud.hpp"
#include "packed.hpp"

namespace dmh {

constexpr int64_t CONVEX = 4;

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

}  // namespace dmh
