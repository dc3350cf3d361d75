// The implicit k-d tree of a point cloud: drake_mh.scene.kernels.pieces.kd_build, step for step
// (the same median-of-three Hoare selection on the same axes), so the same tree.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace dmh {

constexpr int64_t KD_LEAF = 8;  // pieces.py _LEAF: ranges of at most this many points are scanned

struct KdPoint {  // a point and its input row, swapped together (one 32-byte move)
    double p[3];
    int64_t row;
};

// Reorder pts[lo, hi) so that pts[nth] holds the nth-smallest coordinate `axis`, the smaller
// before it and the larger after it: pieces.py _select (Hoare's selection, median of three).
template <int axis>
inline void kd_select_on(KdPoint* pts, int64_t lo, int64_t hi, int64_t nth) {
    while (hi - lo > 1) {
        const double a = pts[lo].p[axis], b = pts[(lo + hi) >> 1].p[axis], c = pts[hi - 1].p[axis];
        const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
        int64_t i = lo, j = hi - 1;
        while (i <= j) {
            while (pts[i].p[axis] < pivot) ++i;
            while (pts[j].p[axis] > pivot) --j;
            if (i <= j) {
                std::swap(pts[i], pts[j]);
                ++i;
                --j;
            }
        }
        if (nth <= j)
            hi = j + 1;
        else if (nth >= i)
            lo = i;
        else
            return;
    }
}

inline void kd_select(KdPoint* pts, int64_t lo, int64_t hi, int64_t nth, int axis) {
    if (axis == 0)
        kd_select_on<0>(pts, lo, hi, nth);
    else if (axis == 1)
        kd_select_on<1>(pts, lo, hi, nth);
    else
        kd_select_on<2>(pts, lo, hi, nth);
}

// The tree of P (N, 3) row-major, written to order (N,), axes (N,), tree (N, 3), boxes (N, 6)
// (pieces.py kd_build: the median of [lo, hi) at (lo + hi) / 2, its split axis the widest side of
// the root's box cut at each median above, boxes of the ranges of more than KD_LEAF points, other
// rows 0). Points must be finite (NaN would stop the selection's scans at the range's ends).
inline void kd_build(const double* P, int64_t N, int64_t* order, int64_t* axes, double* tree, double* boxes) {
    std::vector<KdPoint> pts(N);
    for (int64_t j = 0; j < N; ++j) pts[j] = {{P[3 * j], P[3 * j + 1], P[3 * j + 2]}, j};
    std::fill(axes, axes + N, int64_t(0));
    std::fill(boxes, boxes + 6 * N, 0.0);
    struct Range {
        int64_t lo, hi;
        double box[6];
    };
    std::vector<Range> stack;
    stack.reserve(64);
    std::vector<int64_t> split;  // the split ranges' (lo, mid, hi), parents first
    split.reserve(3 * (N / KD_LEAF + 1));
    Range root{0, N, {}};
    for (int a = 0; a < 3; ++a) {
        root.box[a] = std::numeric_limits<double>::infinity();
        root.box[3 + a] = -std::numeric_limits<double>::infinity();
    }
    for (int64_t j = 0; j < N; ++j)
        for (int a = 0; a < 3; ++a) {
            root.box[a] = std::min(root.box[a], pts[j].p[a]);
            root.box[3 + a] = std::max(root.box[3 + a], pts[j].p[a]);
        }
    stack.push_back(root);
    while (!stack.empty()) {
        Range r = stack.back();
        stack.pop_back();
        if (r.hi - r.lo <= KD_LEAF) continue;
        int axis = 0;
        double widest = -1.0;
        for (int a = 0; a < 3; ++a)
            if (r.box[3 + a] - r.box[a] > widest) axis = a, widest = r.box[3 + a] - r.box[a];
        const int64_t mid = (r.lo + r.hi) >> 1;
        kd_select(pts.data(), r.lo, r.hi, mid, axis);
        axes[mid] = axis;
        split.insert(split.end(), {r.lo, mid, r.hi});
        const double cut = pts[mid].p[axis];
        Range lower = r, upper = r;  // pushed lower first, as pieces.py: the upper half pops first
        lower.hi = mid;
        lower.box[3 + axis] = cut;
        upper.lo = mid + 1;
        upper.box[axis] = cut;
        stack.push_back(lower);
        stack.push_back(upper);
    }
    for (int64_t j = 0; j < N; ++j) {
        order[j] = pts[j].row;
        for (int a = 0; a < 3; ++a) tree[3 * j + a] = pts[j].p[a];
    }
    for (int64_t s = (int64_t)split.size() - 3; s >= 0; s -= 3) {  // children before parents
        const int64_t lo = split[s], mid = split[s + 1], hi = split[s + 2];
        double* box = boxes + 6 * mid;
        for (int a = 0; a < 3; ++a) box[a] = box[3 + a] = pts[mid].p[a];
        const int64_t halves[2][2] = {{lo, mid}, {mid + 1, hi}};
        for (const auto& half : halves) {
            const int64_t c0 = half[0], c1 = half[1];
            if (c1 - c0 > KD_LEAF) {
                const double* child = boxes + 6 * ((c0 + c1) >> 1);
                for (int a = 0; a < 3; ++a) {
                    box[a] = std::min(box[a], child[a]);
                    box[3 + a] = std::max(box[3 + a], child[3 + a]);
                }
            } else {
                for (int64_t j = c0; j < c1; ++j)
                    for (int a = 0; a < 3; ++a) {
                        box[a] = std::min(box[a], pts[j].p[a]);
                        box[3 + a] = std::max(box[3 + a], pts[j].p[a]);
                    }
            }
        }
    }
}

}  // namespace dmh
