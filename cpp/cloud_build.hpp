// A point cloud's shape-table entry (cloud.hpp reads it): drake_mh/scene/kernels/cloud.py
// cloud_table, the same steps on the same values, so the same table.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "cloud.hpp"

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")  // cloud.py builds without fast-math: the same roundings

namespace dmh {

// The bits of v (< 2^CLOUD_MORTON_BITS) spread to every third bit (a table).
inline uint32_t cloud_spread(uint32_t v) {
    struct Table {
        uint32_t bits[1 << CLOUD_MORTON_BITS];
        Table() {
            for (uint32_t v = 0; v < (1u << CLOUD_MORTON_BITS); ++v) {
                bits[v] = 0;
                for (int b = 0; b < CLOUD_MORTON_BITS; ++b) bits[v] |= ((v >> b) & 1u) << (3 * b);
            }
        }
    };
    static const Table table;
    return table.bits[v];
}

// d[q] = min_p ((q - p)^2 + f[p]) over the p < n with a finite f[p] (inf if none): the lower
// envelope of parabolas (Felzenszwalb & Huttenlocher, Theory of Computing 8, 2012, Algorithm 1);
// cloud.py _parabolas. v, z: scratch of n and n + 1.
inline void cloud_parabolas(const double* f, int64_t n, double* d, int64_t* v, double* z) {
    int64_t k = -1;
    const double inf = std::numeric_limits<double>::infinity();
    for (int64_t q = 0; q < n; ++q) {
        if (f[q] == inf) continue;
        const double fq = f[q] + (double)q * (double)q;
        while (k >= 0) {
            const int64_t p = v[k];
            const double s = (fq - (f[p] + (double)p * (double)p)) / (2.0 * (double)(q - p));
            if (s <= z[k])
                --k;
            else
                break;
        }
        ++k;
        v[k] = q;
        z[k] = k == 0 ? -inf : (fq - (f[v[k - 1]] + (double)v[k - 1] * (double)v[k - 1])) / (2.0 * (double)(q - v[k - 1]));
    }
    if (k < 0) {
        std::fill(d, d + n, inf);
        return;
    }
    int64_t j = 0;
    for (int64_t q = 0; q < n; ++q) {
        while (j < k && z[j + 1] < (double)q) ++j;
        d[q] = (double)(q - v[j]) * (double)(q - v[j]) + f[v[j]];
    }
}

// Squared Euclidean distances [cells^2] from each cell of a grid (nx, ny, nz) to the nearest cell
// set in zero (inf if none): exact, one pass per axis (cloud.py distance_transform).
inline void cloud_edt(const std::vector<uint8_t>& zero, int64_t nx, int64_t ny, int64_t nz, std::vector<double>& D) {
    const double inf = std::numeric_limits<double>::infinity();
    D.resize(nx * ny * nz);
    for (int64_t r = 0; r < nx * ny; ++r) {  // along z: the distance to the nearest set cell of the row, two sweeps
        const uint8_t* in = zero.data() + r * nz;
        double* out = D.data() + r * nz;
        double gap = inf;
        for (int64_t l = 0; l < nz; ++l) out[l] = gap = in[l] ? 0.0 : gap + 1.0;
        gap = inf;
        for (int64_t l = nz - 1; l >= 0; --l) {
            gap = in[l] ? 0.0 : gap + 1.0;
            out[l] = std::min(out[l], gap);
        }
        for (int64_t l = 0; l < nz; ++l) out[l] *= out[l];
    }
    const int64_t n_max = std::max(nx, std::max(ny, nz));
    std::vector<double> f(n_max), d(n_max), z(n_max + 1);
    std::vector<int64_t> v(n_max);
    auto pass = [&](int64_t n, int64_t stride, int64_t base) {
        for (int64_t l = 0; l < n; ++l) f[l] = D[base + l * stride];
        cloud_parabolas(f.data(), n, d.data(), v.data(), z.data());
        for (int64_t l = 0; l < n; ++l) D[base + l * stride] = d[l];
    };
    for (int64_t i = 0; i < nx; ++i)
        for (int64_t l = 0; l < nz; ++l) pass(ny, nz, i * ny * nz + l);  // along y
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t l = 0; l < nz; ++l) pass(nx, ny * nz, j * nz + l);  // along x
}

// The table of points P (N, 3) (finite, N >= 1), radius rho [m], grid cell at least h_min [m]
// and about at most max_cells cells: rows of 3 (cloud.py cloud_table); low, high: the points'
// bounding box. N < 2^32 (the sort keys hold the row in 32 bits).
struct CloudTable {
    std::unique_ptr<double[]> data;  // rows x 3
    int64_t rows = 0;
};

inline CloudTable cloud_table(const double* P, int64_t N, double rho, double h_min, double max_cells,
                                       double* low, double* high) {
    const double inf = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) low[a] = inf, high[a] = -inf;
    for (int64_t j = 0; j < N; ++j)
        for (int a = 0; a < 3; ++a) low[a] = std::min(low[a], P[3 * j + a]), high[a] = std::max(high[a], P[3 * j + a]);
    // the grid of distance bounds
    const double volume = (high[0] - low[0] + h_min) * (high[1] - low[1] + h_min) * (high[2] - low[2] + h_min);
    const double h = std::max(h_min, std::pow(volume / max_cells, 1.0 / 3.0));
    int64_t shape[3];
    for (int a = 0; a < 3; ++a) shape[a] = (int64_t)std::floor((high[a] - low[a]) / h) + 1;
    const int64_t nx = shape[0], ny = shape[1], nz = shape[2], n_cells = nx * ny * nz;
    std::vector<uint8_t> near(n_cells, 0), grown;
    for (int64_t j = 0; j < N; ++j) {
        int64_t c[3];
        for (int a = 0; a < 3; ++a) c[a] = std::min((int64_t)((P[3 * j + a] - low[a]) / h), shape[a] - 1);
        near[(c[0] * ny + c[1]) * nz + c[2]] = 1;
    }
    grown.assign(n_cells, 0);  // dilated by one cell, one axis at a time (rows of the other two)
    for (int64_t r = 0; r < nx * ny; ++r) {  // along z
        const uint8_t* in = near.data() + r * nz;
        uint8_t* out = grown.data() + r * nz;
        for (int64_t l = 0; l < nz; ++l)
            out[l] = in[l] | (l > 0 ? in[l - 1] : 0) | (l + 1 < nz ? in[l + 1] : 0);
    }
    for (int64_t i = 0; i < nx; ++i)  // along y: whole rows of z
        for (int64_t j = 0; j < ny; ++j) {
            const uint8_t* in = grown.data() + (i * ny + j) * nz;
            uint8_t* out = near.data() + (i * ny + j) * nz;
            for (int64_t l = 0; l < nz; ++l)
                out[l] = in[l] | (j > 0 ? in[l - nz] : 0) | (j + 1 < ny ? in[l + nz] : 0);
        }
    for (int64_t i = 0; i < nx; ++i) {  // along x: whole planes of (y, z)
        const uint8_t* in = near.data() + i * ny * nz;
        uint8_t* out = grown.data() + i * ny * nz;
        for (int64_t c = 0; c < ny * nz; ++c)
            out[c] = in[c] | (i > 0 ? in[c - ny * nz] : 0) | (i + 1 < nx ? in[c + ny * nz] : 0);
    }
    std::vector<double> D;
    cloud_edt(grown, nx, ny, nz, D);
    // the points in Morton order (stable: equal codes keep their input order)
    const double extent = std::max(high[0] - low[0], std::max(high[1] - low[1], high[2] - low[2]));
    const double scale = extent > 0.0 ? (double)(int64_t(1) << CLOUD_MORTON_BITS) / extent : 0.0;
    const int64_t top = (int64_t(1) << CLOUD_MORTON_BITS) - 1;
    std::vector<uint64_t> key(N), sorted(N);  // code << 32 | row: sorted by code, stable by row
    for (int64_t j = 0; j < N; ++j) {
        uint64_t m = 0;
        for (int a = 0; a < 3; ++a) {
            const int64_t q = std::min((int64_t)((P[3 * j + a] - low[a]) * scale), top);
            m |= (uint64_t)cloud_spread((uint32_t)q) << (2 - a);
        }
        key[j] = m << 32 | (uint64_t)j;
    }
    constexpr int RADIX = 3 * CLOUD_MORTON_BITS / 2;
    std::vector<int32_t> count((size_t(1) << RADIX) + 1);
    for (int shift = 32; shift < 32 + 3 * CLOUD_MORTON_BITS; shift += RADIX) {  // least significant digit first
        std::fill(count.begin(), count.end(), 0);
        for (int64_t j = 0; j < N; ++j) ++count[((key[j] >> shift) & ((1 << RADIX) - 1)) + 1];
        for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
        for (int64_t j = 0; j < N; ++j) sorted[count[(key[j] >> shift) & ((1 << RADIX) - 1)]++] = key[j];
        key.swap(sorted);
    }
    std::vector<uint64_t> code(N);
    std::vector<int64_t> order(N);
    for (int64_t j = 0; j < N; ++j) code[j] = key[j] >> 32, order[j] = (int64_t)(key[j] & 0xffffffffULL);
    // the tree: nodes in preorder, each splitting its range where the highest differing bit of
    // its codes turns 1 (at the middle if all codes are equal)
    struct Frame {
        int64_t lo, hi, parent, side;
    };
    std::vector<int64_t> child;  // 2 per node
    std::vector<Frame> stack{{0, N, -1, 0}};
    auto leaf = [](int64_t lo, int64_t hi) { return -(1 + (lo << CLOUD_COUNT_BITS) + (hi - lo)); };
    while (!stack.empty()) {
        const Frame f = stack.back();
        stack.pop_back();
        const int64_t id = (int64_t)child.size() / 2;
        if (f.parent >= 0) child[2 * f.parent + f.side] = id;
        int64_t split;
        if (code[f.lo] == code[f.hi - 1]) {
            split = (f.lo + f.hi) >> 1;
        } else {
            const uint64_t bit = uint64_t(1) << (63 - __builtin_clzll(code[f.lo] ^ code[f.hi - 1]));
            split = std::partition_point(code.begin() + f.lo, code.begin() + f.hi,
                                         [bit](uint64_t c) { return !(c & bit); }) - code.begin();
        }
        child.push_back(split - f.lo <= CLOUD_LEAF ? leaf(f.lo, split) : 0);
        child.push_back(f.hi - split <= CLOUD_LEAF ? leaf(split, f.hi) : 0);
        if (f.hi - split > CLOUD_LEAF) stack.push_back({split, f.hi, id, 1});
        if (split - f.lo > CLOUD_LEAF) stack.push_back({f.lo, split, id, 0});
    }
    const int64_t M = (int64_t)child.size() / 2;
    const int64_t head = 3 + (n_cells + CLOUD_CELLS_PER_ROW - 1) / CLOUD_CELLS_PER_ROW;
    CloudTable table;
    table.rows = head + N + CLOUD_NODE_ROWS * M;
    table.data.reset(new double[3 * table.rows]);  // every value written below
    double* t = table.data.get();
    t[0] = rho, t[1] = h, t[2] = (double)head;
    for (int a = 0; a < 3; ++a) t[3 + a] = low[a], t[6 + a] = (double)shape[a];
    double* pts = t + 3 * head;
    for (int64_t j = 0; j < N; ++j)
        for (int a = 0; a < 3; ++a) pts[3 * j + a] = P[3 * order[j] + a];
    double* nodes = pts + 3 * N;
    for (int64_t i = M - 1; i >= 0; --i) {  // children after their parents: boxes bottom-up
        double* n = nodes + 3 * CLOUD_NODE_ROWS * i;
        for (int side = 0; side < 2; ++side) {
            const int64_t c = child[2 * i + side];
            double* box = n + 6 * side;
            for (int a = 0; a < 3; ++a) box[a] = inf, box[3 + a] = -inf;
            if (c >= 0) {
                const double* m = nodes + 3 * CLOUD_NODE_ROWS * c;
                for (int a = 0; a < 3; ++a) {
                    box[a] = std::min(m[a], m[6 + a]);
                    box[3 + a] = std::max(m[3 + a], m[9 + a]);
                }
            } else {
                const int64_t v = -c - 1, j0 = v >> CLOUD_COUNT_BITS, j1 = j0 + (v & ((1 << CLOUD_COUNT_BITS) - 1));
                for (int64_t j = j0; j < j1; ++j)
                    for (int a = 0; a < 3; ++a) {
                        box[a] = std::min(box[a], pts[3 * j + a]);
                        box[3 + a] = std::max(box[3 + a], pts[3 * j + a]);
                    }
            }
            n[12 + side] = (double)c;
        }
        n[14] = 0.0;
    }
    for (int64_t c = 9; c < 3 * head; ++c) t[c] = 0.0;
    uint16_t* cells = reinterpret_cast<uint16_t*>(t + 9);  // the cells' values in steps of h / 256, rounded down
    const double step = h / CLOUD_STEPS;
    for (int64_t c = 0; c < n_cells; ++c)
        cells[c] = (uint16_t)std::min(std::floor(std::max(h * std::sqrt(D[c]) - 1e-9, 0.0) / step), CLOUD_SATURATED);
    return table;
}

}  // namespace dmh

#pragma GCC pop_options
