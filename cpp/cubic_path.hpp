// The cubic joint path of drake_mh/trajectories/paths.py: not_a_knot (scipy CubicSpline's
// not-a-knot slopes at the knots, their tridiagonal system solved as LAPACK's dgtsv solves it:
// Gaussian elimination with partial pivoting) and piece_extrema (each piece's exact minimum and
// maximum per joint). The same operations in the same order as there, so the same coefficients
// and extrema up to round-off.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace dmh {

// Solve the tridiagonal system (dl (n-1,), d (n,), du (n-1,), overwritten) for the r columns of
// B (n, r) row-major, in place: LAPACK dgtsv's elimination and back substitution. False where a
// pivot is zero (singular).
inline bool tridiagonal_solve(std::vector<double>& dl, std::vector<double>& d, std::vector<double>& du, double* B,
                              int64_t n, int64_t r) {
    auto eliminate = [&](int64_t i, bool last) {
        if (std::fabs(d[i]) >= std::fabs(dl[i])) {  // no row interchange
            if (d[i] == 0.0) return false;
            const double fact = dl[i] / d[i];
            d[i + 1] -= fact * du[i];
            for (int64_t j = 0; j < r; ++j) B[(i + 1) * r + j] -= fact * B[i * r + j];
            dl[i] = 0.0;
        } else {  // interchange rows i and i + 1
            const double fact = d[i] / dl[i];
            d[i] = dl[i];
            const double temp = d[i + 1];
            d[i + 1] = du[i] - fact * temp;
            if (!last) {
                dl[i] = du[i + 1];
                du[i + 1] = -fact * dl[i];
            }
            du[i] = temp;
            for (int64_t j = 0; j < r; ++j) {
                const double b = B[i * r + j];
                B[i * r + j] = B[(i + 1) * r + j];
                B[(i + 1) * r + j] = b - fact * B[(i + 1) * r + j];
            }
        }
        return true;
    };
    for (int64_t i = 0; i + 2 < n; ++i)
        if (!eliminate(i, false)) return false;
    if (n > 1 && !eliminate(n - 2, true)) return false;
    if (d[n - 1] == 0.0) return false;
    for (int64_t j = 0; j < r; ++j) {
        B[(n - 1) * r + j] /= d[n - 1];
        if (n > 1) B[(n - 2) * r + j] = (B[(n - 2) * r + j] - du[n - 2] * B[(n - 1) * r + j]) / d[n - 2];
        for (int64_t i = n - 3; i >= 0; --i)
            B[i * r + j] = (B[i * r + j] - du[i] * B[(i + 1) * r + j] - dl[i] * B[(i + 2) * r + j]) / d[i];
    }
    return true;
}

// Coefficients c (4, n - 1, nq) (highest power first, scipy's PPoly layout) of the not-a-knot
// cubic spline through P (n, nq) at strictly increasing knots s (n,), n >= 2. False where the
// slopes' system is singular (never for increasing s).
inline bool not_a_knot(const double* s, const double* P, int64_t n, int64_t nq, double* c) {
    const int64_t m = n - 1;
    std::vector<double> dx(m), slope(m * nq), D(n * nq);
    for (int64_t i = 0; i < m; ++i) {
        dx[i] = s[i + 1] - s[i];
        for (int64_t j = 0; j < nq; ++j) slope[i * nq + j] = (P[(i + 1) * nq + j] - P[i * nq + j]) / dx[i];
    }
    if (n == 2) {
        for (int64_t j = 0; j < nq; ++j) D[j] = D[nq + j] = slope[j];
    } else {
        std::vector<double> dl(n - 1), d(n), du(n - 1);
        if (n == 3) {  // the parabola through the three points
            d = {1.0, 2.0 * (dx[0] + dx[1]), 1.0}, du = {1.0, dx[0]}, dl = {dx[1], 1.0};
            for (int64_t j = 0; j < nq; ++j) {
                D[j] = 2.0 * slope[j];
                D[nq + j] = 3.0 * (dx[0] * slope[nq + j] + dx[1] * slope[j]);
                D[2 * nq + j] = 2.0 * slope[nq + j];
            }
        } else {
            const double d0 = s[2] - s[0], d1 = s[n - 1] - s[n - 3];
            d[0] = dx[1], d[n - 1] = dx[m - 2];
            for (int64_t i = 1; i < n - 1; ++i) d[i] = 2.0 * (dx[i - 1] + dx[i]);
            du[0] = d0, dl[n - 2] = d1;
            for (int64_t i = 1; i < n - 1; ++i) du[i] = dx[i - 1];
            for (int64_t i = 0; i < n - 2; ++i) dl[i] = dx[i + 1];
            for (int64_t j = 0; j < nq; ++j) {
                for (int64_t i = 1; i < n - 1; ++i)
                    D[i * nq + j] = 3.0 * (dx[i] * slope[(i - 1) * nq + j] + dx[i - 1] * slope[i * nq + j]);
                D[j] = ((dx[0] + 2.0 * d0) * dx[1] * slope[j] + dx[0] * dx[0] * slope[nq + j]) / d0;
                D[(n - 1) * nq + j] = (dx[m - 1] * dx[m - 1] * slope[(m - 2) * nq + j] +
                                       (2.0 * d1 + dx[m - 1]) * dx[m - 2] * slope[(m - 1) * nq + j]) / d1;
            }
        }
        if (!tridiagonal_solve(dl, d, du, D.data(), n, nq)) return false;
    }
    for (int64_t i = 0; i < m; ++i)
        for (int64_t j = 0; j < nq; ++j) {
            const double sl = slope[i * nq + j], a = D[i * nq + j], b = D[(i + 1) * nq + j];
            const double t = (a + b - 2.0 * sl) / dx[i];
            c[(0 * m + i) * nq + j] = t / dx[i];
            c[(1 * m + i) * nq + j] = (sl - a) / dx[i] - t;
            c[(2 * m + i) * nq + j] = a;
            c[(3 * m + i) * nq + j] = P[i * nq + j];
        }
    return true;
}

// Exact minimum and maximum lo, hi (m, nq) of every piece of the cubic spline c (4, m, nq) on
// its breakpoints x (m + 1,): the ends and the roots of the derivative inside the piece.
inline void piece_extrema(const double* c, const double* x, int64_t m, int64_t nq, double* lo, double* hi) {
    for (int64_t i = 0; i < m; ++i) {
        const double h = x[i + 1] - x[i];
        for (int64_t j = 0; j < nq; ++j) {
            const double c0 = c[i * nq + j], c1 = c[(m + i) * nq + j], c2 = c[(2 * m + i) * nq + j],
                         c3 = c[(3 * m + i) * nq + j];
            const double a3 = 3.0 * c0, a2 = 2.0 * c1, a1 = c2;
            const double v0 = c3, v1 = ((c0 * h + c1) * h + c2) * h + c3;
            double low = std::min(v0, v1), high = std::max(v0, v1);
            const double disc = a2 * a2 - 4.0 * a3 * a1;
            const double sq = std::sqrt(std::max(disc, 0.0));
            const double roots[3] = {(-a2 + sq) / (2.0 * a3), (-a2 - sq) / (2.0 * a3), -a1 / a2};
            for (const double y : roots)
                if (std::isfinite(y) && y > 0.0 && y < h && disc >= 0.0) {
                    const double v = ((c0 * y + c1) * y + c2) * y + c3;
                    low = std::min(low, v), high = std::max(high, v);
                }
            lo[i * nq + j] = low, hi[i * nq + j] = high;
        }
    }
}

}  // namespace dmh
