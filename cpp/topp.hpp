// Time-optimal path parameterization by reachability analysis (TOPP-RA: Pham & Pham, "A new
// approach to time-optimal path parameterization based on reachability analysis", IEEE T-RO 2018):
// the backward pass of controllable sets (Algorithm 1's K_i, eq. 21) and the greedy forward pass
// (eq. 23), each stage's 2-variable LP solved exactly by Seidel's incremental algorithm. The
// answers of the toppra package's TOPPRA with solver_wrapper="seidel" (toppra/algorithm/
// reachabilitybased/reachability_algorithm.py, time_optimal_algorithm.py and
// toppra/solverwrapper/cy_seidel_solverwrapper.pyx): the same LPs with the same warm starts,
// tolerances, 1-D forward steps, retries and clipping, in the same order, without contraction.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace dmh {

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")  // the package's Cython is compiled without fused multiply-adds

namespace topp {

// cy_seidel_solverwrapper.pyx's constants
constexpr double LP_TINY = 1e-10, LP_SMALL = 1e-8;
constexpr double VAR_MIN = -100000000.0, VAR_MAX = 100000000.0, LP_INF = 10000000000.0;
// toppra/constants.py's, used by the algorithm
constexpr double ALG_TINY = 1e-8, ALG_SMALL = 1e-5;
constexpr int MAX_TRIES = 10;

struct LpSol {
    int result = 0;  // 1 solved, 0 infeasible
    double optvar[2] = {0, 0};
    int64_t active_c[2] = {0, 0};
};

// max v0 x  s.t.  a x + b <= 0 (n rows), low <= x <= high (cy_solve_lp1d). active_c[0] the row at
// the optimum, -1 / -2 the lower / upper bound.
inline LpSol lp1d(double v0, int64_t n, const double* a, const double* b, double low, double high) {
    double cur_min = low, cur_max = high;
    int64_t active_min = -1, active_max = -2;
    for (int64_t i = 0; i < n; ++i) {
        if (a[i] > LP_TINY) {
            const double x = -b[i] / a[i];
            if (x < cur_max) cur_max = x, active_max = i;
        } else if (a[i] < -LP_TINY) {
            const double x = -b[i] / a[i];
            if (x > cur_min) cur_min = x, active_min = i;
        }  // |a| <= TINY: ignored
    }
    LpSol sol;
    if (cur_min > cur_max) return sol;
    sol.result = 1;
    const bool lower = std::fabs(v0) < LP_TINY || v0 < 0;
    sol.optvar[0] = lower ? cur_min : cur_max;
    sol.active_c[0] = lower ? active_min : active_max;
    return sol;
}

// Workspace of lp2d for up to nrows rows (allocated once per solve).
struct Lp2dWork {
    std::vector<int64_t> index_map;
    std::vector<double> a_1d, b_1d;
    explicit Lp2dWork(int64_t nrows) : index_map(nrows), a_1d(nrows + 4), b_1d(nrows + 4) {}
};

// max v . (u, x)  s.t.  a u + b x + c <= 0 (nrows rows), low <= (u, x) <= high (cy_solve_lp2d):
// Seidel's incremental algorithm, the rows active at the previous solve (active_c) first. A
// violated row becomes an equality and the rows before it are projected onto its line (a 1-D LP);
// parallel rows are feasible or not within LP_SMALL. active_c: bounds -1..-4 (low u, high u,
// low x, high x), else row indices.
inline LpSol lp2d(const double v[2], int64_t nrows, const double* a, const double* b, const double* c,
                  const double low[2], const double high[2], const int64_t active_c[2], Lp2dWork& w) {
    LpSol sol;
    double cur[2];
    for (int i = 0; i < 2; ++i) {
        if (low[i] > high[i]) return sol;
        if (v[i] > LP_TINY) {
            cur[i] = high[i];
            sol.active_c[i] = i == 0 ? -2 : -4;
        } else {
            cur[i] = low[i];
            sol.active_c[i] = i == 0 ? -1 : -3;
        }
    }
    int64_t* index_map = w.index_map.data();
    if (active_c[0] >= 0 && active_c[0] < nrows && active_c[1] >= 0 && active_c[1] < nrows &&
        active_c[0] != active_c[1]) {
        index_map[0] = active_c[1], index_map[1] = active_c[0];
        int64_t row = 2;
        for (int64_t i = 0; i < nrows; ++i)
            if (i != active_c[0] && i != active_c[1]) index_map[row++] = i;
    } else {
        for (int64_t i = 0; i < nrows; ++i) index_map[i] = i;
    }
    double* a_1d = w.a_1d.data();
    double* b_1d = w.b_1d.data();
    for (int64_t k = 0; k < nrows; ++k) {
        const int64_t i = index_map[k];
        if (a[i] * cur[0] + b[i] * cur[1] + c[i] < LP_TINY) continue;
        sol.active_c[0] = i;
        const double norm2 = a[i] * a[i] + b[i] * b[i];
        const double zp0 = -a[i] * c[i] / norm2, zp1 = -b[i] * c[i] / norm2;  // the origin projected
        const double d0 = -b[i], d1 = a[i];                                   // along the line
        const double v_1d = d0 * v[0] + d1 * v[1];
        const int64_t n_1d = 4 + k;
        for (int64_t j = 0; j < n_1d; ++j) {
            double aj, bj, cj;
            if (j == k) aj = -1, bj = 0, cj = low[0];
            else if (j == k + 1) aj = 1, bj = 0, cj = -high[0];
            else if (j == k + 2) aj = 0, bj = -1, cj = low[1];
            else if (j == k + 3) aj = 0, bj = 1, cj = -high[1];
            else aj = a[index_map[j]], bj = b[index_map[j]], cj = c[index_map[j]];
            const double denom = d0 * aj + d1 * bj;
            if (denom > LP_TINY) {
                const double t_limit = -(cj + zp1 * bj + zp0 * aj) / denom;
                a_1d[j] = 1.0, b_1d[j] = -t_limit;
            } else if (denom < -LP_TINY) {
                const double t_limit = -(cj + zp1 * bj + zp0 * aj) / denom;
                a_1d[j] = -1.0, b_1d[j] = t_limit;
            } else {  // parallel to the new line: feasible everywhere on it, or nowhere
                if (cj + zp1 * bj + zp0 * aj > LP_SMALL) return LpSol{};
                a_1d[j] = 0, b_1d[j] = -1.0;
            }
        }
        const LpSol s1 = lp1d(v_1d, n_1d, a_1d, b_1d, -LP_INF, LP_INF);
        if (s1.result == 0) return LpSol{};
        cur[0] = zp0 + s1.optvar[0] * d0;
        cur[1] = zp1 + s1.optvar[0] * d1;
        const int64_t act = s1.active_c[0];
        if (act >= 0 && act < k) sol.active_c[1] = index_map[act];
        else if (act >= k && act < k + 4) sol.active_c[1] = -1 - (act - k);
        else return LpSol{};  // the 1-D problem's own far bound: unbounded along the line
    }
    sol.result = 1;
    sol.optvar[0] = cur[0], sol.optvar[1] = cur[1];
    return sol;
}

}  // namespace topp

// TOPP-RA on N + 1 gridpoints gp (increasing) from rest to rest. Stage i's rows (R of them)
// A, B, C (N + 1, R) row-major: a u + b x + c <= 0 in u = s̈ (constant on [s_i, s_{i+1}]) and
// x = ṡ² at s_i; x_lo, x_hi (N + 1,) bounds on x_i (-inf / inf: none). Writes the controllable sets
// K (N + 1, 2) (lower, upper x), xs (N + 1,) the squared path speeds and us (N,) the path
// accelerations. Returns -1 on success; otherwise the stage whose controllable set is empty
// (backward pass), 0 when the start is not controllable, or the stage where the forward pass
// failed after its retries (toppra returns no parameterization in each case).
inline int64_t topp_ra(const double* gp, int64_t N1, const double* A, const double* B, const double* C, int64_t R,
                       const double* x_lo, const double* x_hi, double* K, double* xs, double* us) {
    using namespace topp;
    const int64_t N = N1 - 1, nC = R + 2;  // rows 0, 1: x + 2 Δ u within K_{i+1}
    std::vector<double> a(nC), b(nC), c(nC), bx_c(nC);
    Lp2dWork work(nC);
    int64_t active_up[2] = {0, 0}, active_down[2] = {0, 0};
    auto load = [&](int64_t i, double x_next_min, double x_next_max) {
        const double delta = gp[i + 1] - gp[i];
        a[0] = -2 * delta, b[0] = -1.0, c[0] = x_next_min;
        a[1] = 2 * delta, b[1] = 1.0, c[1] = -x_next_max;
        for (int64_t r = 0; r < R; ++r)
            a[r + 2] = A[i * R + r], b[r + 2] = B[i * R + r], c[r + 2] = C[i * R + r];
    };
    auto bounds = [&](int64_t i, double low[2], double high[2]) {
        low[0] = VAR_MIN, high[0] = VAR_MAX;
        low[1] = x_lo[i] > VAR_MIN ? x_lo[i] : VAR_MIN;  // dbl_max / dbl_min as the wrapper's
        high[1] = x_hi[i] < VAR_MAX ? x_hi[i] : VAR_MAX;
    };
    K[2 * N] = 0.0, K[2 * N + 1] = 0.0;  // sd_end = 0
    for (int64_t i = N - 1; i >= 0; --i) {
        load(i, K[2 * (i + 1)], K[2 * (i + 1) + 1]);
        double low[2], high[2];
        bounds(i, low, high);
        const double v_max_x[2] = {-1e-9, 1.0}, v_min_x[2] = {1e-9, -1.0};
        const LpSol up = lp2d(v_max_x, nC, a.data(), b.data(), c.data(), low, high, active_down, work);
        double x_upper = NAN, x_lower = NAN;
        if (up.result) x_upper = up.optvar[1], active_down[0] = up.active_c[0], active_down[1] = up.active_c[1];
        const LpSol lo = lp2d(v_min_x, nC, a.data(), b.data(), c.data(), low, high, active_up, work);
        if (lo.result) x_lower = lo.optvar[1], active_up[0] = lo.active_c[0], active_up[1] = lo.active_c[1];
        K[2 * i] = x_lower < 0 ? 0.0 : x_lower, K[2 * i + 1] = x_upper;
        if (std::isnan(K[2 * i]) || std::isnan(K[2 * i + 1])) return i;
    }
    const double x_start = 0.0;  // sd_start = 0
    if (x_start + ALG_SMALL < K[0] || K[1] + ALG_SMALL < x_start) return 0;
    xs[0] = x_start;
    int tries = 0;
    for (int64_t i = 0; i < N;) {
        const double delta = gp[i + 1] - gp[i];
        load(i, K[2 * (i + 1)], K[2 * (i + 1) + 1]);
        double low[2], high[2];
        bounds(i, low, high);
        for (int64_t r = 0; r < nC; ++r) bx_c[r] = b[r] * xs[i] + c[r];
        const LpSol s = lp1d(2 * delta, nC, a.data(), bx_c.data(), low[0], high[0]);
        if (!s.result) {  // slightly infeasible by round-off: lower x_i a little and try again
            if (tries >= MAX_TRIES) return i;
            xs[i] = std::fmax(xs[i] - ALG_TINY, 0.999 * xs[i]);
            ++tries;
            continue;
        }
        tries = 0;
        us[i] = s.optvar[0];
        double x_next = xs[i] + 2 * delta * us[i];
        x_next = std::fmax(x_next - ALG_TINY, 0.9999 * x_next);
        xs[i + 1] = std::fmin(K[2 * (i + 1) + 1], std::fmax(K[2 * (i + 1)], x_next));
        ++i;
    }
    return -1;
}

#pragma GCC pop_options

}  // namespace dmh
