// Certified GJK between two convex cores (a point, segment, box, cylinder, ellipsoid or vertex
// hull, each grown by a ball elsewhere): drake_mh/scene/kernels/gjk.py step for step (the
// certificate, the sub-algorithm and the stopping rules are described there). Compiled without
// floating-point contraction, as numba compiles that kernel, so the two give the same numbers.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")

namespace dmh {
namespace gjk {

constexpr int64_t POINT = 0, SEGMENT = 1, BOX = 2, CYLINDER = 3, ELLIPSOID = 4, HULL = 5;
constexpr int SEPARATED = 1, INTERSECTING = 2, NOT_CONVERGED = 3;
constexpr int MAX_ITERATIONS = 128;

// A point of the core (its own frame) farthest along d, into out (3,); a hull's vertices are
// vertices[start:start + count] (rows of 3).
inline void support(int64_t kind, const double* dims, const double* vertices, int64_t start, int64_t count, double dx,
                    double dy, double dz, double* out) {
    if (kind == POINT) {
        out[0] = out[1] = out[2] = 0.0;
    } else if (kind == SEGMENT) {
        out[0] = out[1] = 0.0;
        out[2] = dz >= 0.0 ? dims[0] : -dims[0];
    } else if (kind == BOX) {
        out[0] = dx >= 0.0 ? dims[0] : -dims[0];
        out[1] = dy >= 0.0 ? dims[1] : -dims[1];
        out[2] = dz >= 0.0 ? dims[2] : -dims[2];
    } else if (kind == CYLINDER) {
        const double rho = std::sqrt(dx * dx + dy * dy);
        if (rho > 0.0) {
            out[0] = dims[0] * dx / rho;
            out[1] = dims[0] * dy / rho;
        } else {
            out[0] = out[1] = 0.0;
        }
        out[2] = dz >= 0.0 ? dims[1] : -dims[1];
    } else if (kind == ELLIPSOID) {
        const double ax = dims[0] * dims[0] * dx, ay = dims[1] * dims[1] * dy, az = dims[2] * dims[2] * dz;
        const double norm = std::sqrt(ax * dx + ay * dy + az * dz);
        if (norm > 0.0) {
            out[0] = ax / norm;
            out[1] = ay / norm;
            out[2] = az / norm;
        } else {
            out[0] = dims[0];
            out[1] = out[2] = 0.0;
        }
    } else {  // HULL
        double best = -std::numeric_limits<double>::infinity();
        int64_t j = start;
        for (int64_t i = start; i < start + count; ++i) {
            const double s = vertices[3 * i] * dx + vertices[3 * i + 1] * dy + vertices[3 * i + 2] * dz;
            if (s > best) {
                best = s;
                j = i;
            }
        }
        out[0] = vertices[3 * j];
        out[1] = vertices[3 * j + 1];
        out[2] = vertices[3 * j + 2];
    }
}

// Support point of core A posed at (R (3, 3) row-major, p) in B's frame, along d (B's frame).
inline void support_a(int64_t kind, const double* dims, const double* R, const double* p, const double* vertices,
                      int64_t start, int64_t count, double dx, double dy, double dz, double* out) {
    double local[3];
    support(kind, dims, vertices, start, count, R[0] * dx + R[3] * dy + R[6] * dz, R[1] * dx + R[4] * dy + R[7] * dz,
            R[2] * dx + R[5] * dy + R[8] * dz, local);
    for (int i = 0; i < 3; ++i) out[i] = p[i] + R[3 * i] * local[0] + R[3 * i + 1] * local[1] + R[3 * i + 2] * local[2];
}

// Weights lam (4,) of the point of conv(W[:n]) nearest the origin; returns the subset mask.
inline int nearest_on_simplex(const double (*W)[3], int n, double* lam) {
    double best = std::numeric_limits<double>::infinity();
    int best_mask = 1;
    int idx[4];
    double mu[4];
    for (int mask = 1; mask < (1 << n); ++mask) {
        int k = 0;
        for (int i = 0; i < n; ++i)
            if (mask & (1 << i)) idx[k++] = i;
        const double* W0 = W[idx[0]];
        if (k == 1) {
            mu[0] = 1.0;
        } else if (k == 2) {
            const double d0 = W[idx[1]][0] - W0[0], d1 = W[idx[1]][1] - W0[1], d2 = W[idx[1]][2] - W0[2];
            const double dd = d0 * d0 + d1 * d1 + d2 * d2;
            if (dd <= 1e-300) continue;
            const double t = -(W0[0] * d0 + W0[1] * d1 + W0[2] * d2) / dd;
            mu[0] = 1.0 - t;
            mu[1] = t;
        } else if (k == 3) {
            const double a0 = W[idx[1]][0] - W0[0], a1 = W[idx[1]][1] - W0[1], a2 = W[idx[1]][2] - W0[2];
            const double b0 = W[idx[2]][0] - W0[0], b1 = W[idx[2]][1] - W0[1], b2 = W[idx[2]][2] - W0[2];
            const double g00 = a0 * a0 + a1 * a1 + a2 * a2, g01 = a0 * b0 + a1 * b1 + a2 * b2,
                         g11 = b0 * b0 + b1 * b1 + b2 * b2;
            const double r0 = -(W0[0] * a0 + W0[1] * a1 + W0[2] * a2), r1 = -(W0[0] * b0 + W0[1] * b1 + W0[2] * b2);
            const double det = g00 * g11 - g01 * g01;
            if (det <= 1e-12 * g00 * g11 || det <= 1e-300) continue;
            const double s = (r0 * g11 - r1 * g01) / det, t = (g00 * r1 - g01 * r0) / det;
            mu[0] = 1.0 - s - t;
            mu[1] = s;
            mu[2] = t;
        } else {
            const double a0 = W[idx[1]][0] - W0[0], a1 = W[idx[1]][1] - W0[1], a2 = W[idx[1]][2] - W0[2];
            const double b0 = W[idx[2]][0] - W0[0], b1 = W[idx[2]][1] - W0[1], b2 = W[idx[2]][2] - W0[2];
            const double c0 = W[idx[3]][0] - W0[0], c1 = W[idx[3]][1] - W0[1], c2 = W[idx[3]][2] - W0[2];
            const double x0 = b1 * c2 - b2 * c1, x1 = b2 * c0 - b0 * c2, x2 = b0 * c1 - b1 * c0;  // b x c
            const double det = a0 * x0 + a1 * x1 + a2 * x2;
            const double scale = std::sqrt(a0 * a0 + a1 * a1 + a2 * a2) * std::sqrt(b0 * b0 + b1 * b1 + b2 * b2) *
                                 std::sqrt(c0 * c0 + c1 * c1 + c2 * c2);
            if (std::fabs(det) <= 1e-12 * scale || scale <= 1e-300) continue;
            const double w0 = -W0[0], w1 = -W0[1], w2 = -W0[2];  // [a b c] (s, t, u) = -W0 (Cramer)
            const double s = (w0 * x0 + w1 * x1 + w2 * x2) / det;
            const double t = (a0 * (w1 * c2 - w2 * c1) + a1 * (w2 * c0 - w0 * c2) + a2 * (w0 * c1 - w1 * c0)) / det;
            const double u = (a0 * (b1 * w2 - b2 * w1) + a1 * (b2 * w0 - b0 * w2) + a2 * (b0 * w1 - b1 * w0)) / det;
            mu[0] = 1.0 - s - t - u;
            mu[1] = s;
            mu[2] = t;
            mu[3] = u;
        }
        bool ok = true;
        for (int j = 0; j < k; ++j)
            if (!(mu[j] > 0.0)) ok = false;
        if (!ok) continue;
        double x0 = 0.0, x1 = 0.0, x2 = 0.0;
        for (int j = 0; j < k; ++j) {
            x0 += mu[j] * W[idx[j]][0];
            x1 += mu[j] * W[idx[j]][1];
            x2 += mu[j] * W[idx[j]][2];
        }
        const double norm2 = x0 * x0 + x1 * x1 + x2 * x2;
        if (norm2 < best) {
            best = norm2;
            best_mask = mask;
            for (int i = 0; i < 4; ++i) lam[i] = 0.0;
            for (int j = 0; j < k; ++j) lam[idx[j]] = mu[j];
        }
    }
    if (best == std::numeric_limits<double>::infinity()) {  // every subset degenerate: the nearest point
        auto n2 = [&](int i) { return W[i][0] * W[i][0] + W[i][1] * W[i][1] + W[i][2] * W[i][2]; };
        int j = 0;
        for (int i = 1; i < n; ++i)
            if (n2(i) < n2(j)) j = i;
        for (int i = 0; i < 4; ++i) lam[i] = 0.0;
        lam[j] = 1.0;
        best_mask = 1 << j;
    }
    return best_mask;
}

// Distance between core A (pose R_BA (3, 3) row-major, p_BA in B's frame) and core B: writes
// out (8,) = lower bound, upper bound, nearest points on A and on B (B's frame); returns
// SEPARATED, INTERSECTING or NOT_CONVERGED (gjk.py gjk). A hull B reads its start and count
// from dims_b[0], dims_b[1].
inline int distance(int64_t kind_a, const double* dims_a, const double* R_BA, const double* p_BA,
                    const double* vertices, int64_t start, int64_t count, int64_t kind_b, const double* dims_b,
                    double tol, double* out) {
    double W[4][3], WA[4][3], WB[4][3], lam[4] = {0.0, 0.0, 0.0, 0.0}, a[3], b[3];
    const int64_t start_b = kind_b == HULL ? (int64_t)dims_b[0] : 0, count_b = kind_b == HULL ? (int64_t)dims_b[1] : 0;
    double dx = p_BA[0], dy = p_BA[1], dz = p_BA[2];
    if (dx * dx + dy * dy + dz * dz < 1e-30) dx = 1.0, dy = 0.0, dz = 0.0;
    support_a(kind_a, dims_a, R_BA, p_BA, vertices, start, count, -dx, -dy, -dz, a);
    support(kind_b, dims_b, vertices, start_b, count_b, dx, dy, dz, b);
    int n = 1;
    for (int i = 0; i < 3; ++i) WA[0][i] = a[i], WB[0][i] = b[i], W[0][i] = a[i] - b[i];
    double v0 = W[0][0], v1 = W[0][1], v2 = W[0][2];
    double pa0 = a[0], pa1 = a[1], pa2 = a[2], pb0 = b[0], pb1 = b[1], pb2 = b[2];
    double lb = -std::numeric_limits<double>::infinity();
    int status = NOT_CONVERGED;
    for (int it = 0; it < MAX_ITERATIONS; ++it) {
        const double vv = v0 * v0 + v1 * v1 + v2 * v2, vn = std::sqrt(vv);
        if (vn <= 1e-300) {
            status = lb < -tol ? INTERSECTING : SEPARATED;
            break;
        }
        support_a(kind_a, dims_a, R_BA, p_BA, vertices, start, count, -v0, -v1, -v2, a);
        support(kind_b, dims_b, vertices, start_b, count_b, v0, v1, v2, b);
        const double w0 = a[0] - b[0], w1 = a[1] - b[1], w2 = a[2] - b[2];
        const double lower = (v0 * w0 + v1 * w1 + v2 * w2) / vn;
        if (lower > lb) lb = lower;
        if (vn - lb <= tol) {
            status = SEPARATED;
            break;
        }
        bool repeated = false;
        for (int j = 0; j < n; ++j)
            if (W[j][0] == w0 && W[j][1] == w1 && W[j][2] == w2) repeated = true;
        if (repeated) break;  // no new support point: round-off stalls the search
        W[n][0] = w0, W[n][1] = w1, W[n][2] = w2;
        for (int i = 0; i < 3; ++i) WA[n][i] = a[i], WB[n][i] = b[i];
        ++n;
        const int mask = nearest_on_simplex(W, n, lam);
        double c0 = 0.0, c1 = 0.0, c2 = 0.0;
        for (int j = 0; j < n; ++j)
            if (mask & (1 << j)) {
                c0 += lam[j] * W[j][0];
                c1 += lam[j] * W[j][1];
                c2 += lam[j] * W[j][2];
            }
        if (c0 * c0 + c1 * c1 + c2 * c2 >= vv) break;  // no progress (round-off): keep the last point
        v0 = c0, v1 = c1, v2 = c2;
        pa0 = pa1 = pa2 = pb0 = pb1 = pb2 = 0.0;
        int m = 0;
        for (int j = 0; j < n; ++j)
            if (mask & (1 << j)) {
                const double lj = lam[j];
                pa0 += lj * WA[j][0], pa1 += lj * WA[j][1], pa2 += lj * WA[j][2];
                pb0 += lj * WB[j][0], pb1 += lj * WB[j][1], pb2 += lj * WB[j][2];
                for (int i = 0; i < 3; ++i) W[m][i] = W[j][i], WA[m][i] = WA[j][i], WB[m][i] = WB[j][i];
                ++m;
            }
        n = m;
        if (n == 4) {  // the origin is inside the tetrahedron
            v0 = v1 = v2 = 0.0;
            status = lb < -tol ? INTERSECTING : SEPARATED;
            break;
        }
    }
    const double ub = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
    if (status == NOT_CONVERGED && ub - lb <= tol) status = SEPARATED;
    out[0] = lb, out[1] = ub;
    out[2] = pa0, out[3] = pa1, out[4] = pa2;
    out[5] = pb0, out[6] = pb1, out[7] = pb2;
    return status;
}

}  // namespace gjk
}  // namespace dmh

#pragma GCC pop_options
