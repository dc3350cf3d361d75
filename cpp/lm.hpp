// Batched damped least-squares / Levenberg-Marquardt IK of drake_mh/ik/lm.py (lm_run, lm_step):
// the same row step, restarts and counter-based starts, so the same iterates and answers. FK and
// Jacobian per candidate from fk.hpp's one-configuration entry.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "fk.hpp"

namespace dmh {

constexpr int64_t LM_RUNNING = 0, LM_CONVERGED = 1, LM_STALLED = 2;

// random.py uniform_at: draw n of the SplitMix64 stream started at seed, uniform in [0, 1).
inline double uniform_at(uint64_t seed, uint64_t n) {
    uint64_t z = seed + (n + 1) * 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z = z ^ (z >> 31);
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

// The candidates' state (lm.py BatchLM), row-major arrays of the caller: K rows, nq joints.
struct LMState {
    int64_t K, nq;
    double *Qt, *Qa, *Ea, *Ja, *fa, *lam;  // (K, nq), (K, nq), (K, 6), (K, 6, nq), (K,), (K,)
    int64_t *stall, *iters, *status;       // (K,)
    bool* fresh;                           // (K,)
    double* Qn;                            // (K, nq) the next trial points
    double* r;                             // (nq,) scratch
};

// The problem and settings (lm.py _lm_row's arguments that stay fixed).
struct LMProblem {
    const double *p_t, *R_t;  // (3,), (3, 3)
    bool has_rot;
    double w_o;
    const double *lower, *upper;  // (nq,)
    bool adaptive;
    double lam_down, lam_up, lam_min, lam_max;
    int64_t max_iter, stall_iters;
    bool project, error_damping;
    double ref_gain;
    const double* q_ref;  // (nq,)
    double tol_p2, tol_o2;
    const bool* revolute;  // (nq,)
};

// e (6,) = [w; dp] for the pose T (4, 4) (lm.py _pose_error).
inline void pose_error(const double* T, const LMProblem& P, double* e) {
    e[3] = P.p_t[0] - T[3], e[4] = P.p_t[1] - T[7], e[5] = P.p_t[2] - T[11];
    if (!P.has_rot) {
        e[0] = e[1] = e[2] = 0.0;
        return;
    }
    double E[9];
    const double* R = P.R_t;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) E[3 * i + j] = R[3 * i] * T[4 * j] + R[3 * i + 1] * T[4 * j + 1] + R[3 * i + 2] * T[4 * j + 2];
    const double wx = 0.5 * (E[7] - E[5]), wy = 0.5 * (E[2] - E[6]), wz = 0.5 * (E[3] - E[1]);
    const double s = std::sqrt(wx * wx + wy * wy + wz * wz);
    const double c = 0.5 * (E[0] + E[4] + E[8] - 1.0);
    const double theta = std::atan2(s, c);
    if (s > 1e-9) {
        const double scale = theta / s;
        e[0] = scale * wx, e[1] = scale * wy, e[2] = scale * wz;
    } else if (c > 0.0) {  // theta ~ s: the skew part is the rotation vector to second order
        e[0] = wx, e[1] = wy, e[2] = wz;
    } else {  // theta ~ pi: axis from the largest column of (E + I) / 2 = a a^T
        int i = 0;
        for (int j = 1; j < 3; ++j)
            if (E[4 * j] > E[4 * i]) i = j;
        const double d = std::sqrt(std::max(0.5 * (E[4 * i] + 1.0), 1e-300));
        for (int j = 0; j < 3; ++j) e[j] = M_PI * 0.5 * (E[3 * j + i] + (j == i ? 1.0 : 0.0)) / d;
    }
}

// Revolute coordinates of q outside the limits moved by whole turns into them (lm.py
// _into_limits); whether every coordinate is then within its limits.
inline bool into_limits(double* q, const LMProblem& P, int64_t nq) {
    for (int64_t j = 0; j < nq; ++j) {
        double v = q[j];
        if (P.lower[j] <= v && v <= P.upper[j]) continue;
        if (!P.revolute[j]) return false;
        const double period = 2.0 * M_PI;
        double r = std::fmod(v - P.lower[j], period);  // Python's %: the sign of the divisor
        if (r < 0.0) r += period;
        v = P.lower[j] + r;
        if (v > P.upper[j]) return false;
        q[j] = v;
    }
    return true;
}

// One iteration of row k (lm.py _lm_row) at the trial point's pose T (4, 4) and Jacobian J (6, nq);
// whether it converged.
inline bool lm_row(int64_t k, const double* T, const double* J, LMState& S, const LMProblem& P) {
    const int64_t nq = S.nq, r0 = P.has_rot ? 0 : 3, m = 6 - r0;
    double e[6], A[36], L[36], y[6], z[6] = {0, 0, 0, 0, 0, 0};
    double* r = S.r;
    double* Qt = S.Qt + k * nq;
    double* Qa = S.Qa + k * nq;
    double* Ea = S.Ea + k * 6;
    double* Ja = S.Ja + k * 6 * nq;
    double* Qn = S.Qn + k * nq;
    for (int64_t j = 0; j < nq; ++j) Qn[j] = Qt[j];  // default next trial: stay
    pose_error(T, P, e);
    double f = 0.0;
    for (int64_t i = r0; i < 6; ++i) f += (i < 3 ? P.w_o * P.w_o : 1.0) * e[i] * e[i];
    if (!std::isfinite(f)) {
        S.status[k] = LM_STALLED;
        return false;
    }
    if (S.fresh[k] || !P.adaptive || f < S.fa[k]) {
        if (!S.fresh[k] && f > 0.9 * S.fa[k])
            S.stall[k] += 1;
        else
            S.stall[k] = 0;
        if (P.adaptive && !S.fresh[k]) S.lam[k] = std::max(S.lam[k] * P.lam_down, P.lam_min);
        for (int64_t j = 0; j < nq; ++j) Qa[j] = Qt[j];
        for (int i = 0; i < 6; ++i) {
            Ea[i] = e[i];
            for (int64_t j = 0; j < nq; ++j) Ja[i * nq + j] = J[i * nq + j];
        }
        S.fa[k] = f;
        S.fresh[k] = false;
    } else {
        S.lam[k] *= P.lam_up;
        S.stall[k] += 1;
    }
    S.iters[k] += 1;
    const double ep2 = Ea[3] * Ea[3] + Ea[4] * Ea[4] + Ea[5] * Ea[5];
    const double eo2 = Ea[0] * Ea[0] + Ea[1] * Ea[1] + Ea[2] * Ea[2];
    if (ep2 <= P.tol_p2 && eo2 <= P.tol_o2) {
        if (!P.project && !into_limits(Qa, P, nq)) {
            S.status[k] = LM_STALLED;  // converged outside the limits: a new start
            return false;
        }
        S.status[k] = LM_CONVERGED;
        return true;
    }
    if (S.iters[k] >= P.max_iter || S.lam[k] > P.lam_max || S.stall[k] >= P.stall_iters) {
        S.status[k] = LM_STALLED;
        return false;
    }
    S.status[k] = LM_RUNNING;
    auto weight = [&](int64_t a) { return a + r0 < 3 ? P.w_o : 1.0; };
    for (int64_t a = 0; a < m; ++a) {  // A = Jw Jw^T + lambda I over the task rows
        for (int64_t b = 0; b <= a; ++b) {
            double s = 0.0;
            for (int64_t j = 0; j < nq; ++j) s += Ja[(a + r0) * nq + j] * Ja[(b + r0) * nq + j];
            A[6 * a + b] = weight(a) * weight(b) * s;
        }
        A[7 * a] += P.error_damping ? S.lam[k] * S.fa[k] : S.lam[k];
    }
    for (int64_t a = 0; a < m; ++a) {  // Cholesky A = L L^T
        for (int64_t b = 0; b <= a; ++b) {
            double s = A[6 * a + b];
            for (int64_t c = 0; c < b; ++c) s -= L[6 * a + c] * L[6 * b + c];
            if (a == b) {
                if (s <= 1e-300) {
                    S.status[k] = LM_STALLED;
                    return false;
                }
                L[7 * a] = std::sqrt(s);
            } else {
                L[6 * a + b] = s / L[7 * b];
            }
        }
    }
    const bool ref = P.ref_gain > 0.0;
    for (int64_t a = 0; a < m; ++a) y[a] = weight(a) * Ea[a + r0];  // rhs y = e_w
    if (ref) {
        for (int64_t j = 0; j < nq; ++j) r[j] = P.ref_gain * (P.q_ref[j] - Qa[j]);
        for (int64_t a = 0; a < m; ++a) {
            double s = 0.0;
            for (int64_t j = 0; j < nq; ++j) s += Ja[(a + r0) * nq + j] * r[j];
            z[a] = weight(a) * s;
        }
    }
    for (int64_t a = 0; a < m; ++a) {  // solve L L^T y = y (and z)
        double s = y[a], t = ref ? z[a] : 0.0;
        for (int64_t c = 0; c < a; ++c) s -= L[6 * a + c] * y[c], t -= L[6 * a + c] * z[c];
        y[a] = s / L[7 * a], z[a] = t / L[7 * a];
    }
    for (int64_t a = m - 1; a >= 0; --a) {
        double s = y[a], t = z[a];
        for (int64_t c = a + 1; c < m; ++c) s -= L[6 * c + a] * y[c], t -= L[6 * c + a] * z[c];
        y[a] = s / L[7 * a], z[a] = t / L[7 * a];
    }
    for (int64_t j = 0; j < nq; ++j) {
        double dq = 0.0;
        for (int64_t a = 0; a < m; ++a) dq += weight(a) * Ja[(a + r0) * nq + j] * (y[a] - (ref ? z[a] : 0.0));
        if (ref) dq += r[j];
        double v = Qa[j] + dq;
        if (!std::isfinite(v)) {
            S.status[k] = LM_STALLED;
            v = Qa[j];
        }
        Qn[j] = P.project ? std::min(std::max(v, P.lower[j]), P.upper[j]) : v;
    }
    return false;
}

// lm.py lm_step: one iteration of every row at the poses T (K, 4, 4) and Jacobians J (K, 6, nq)
// of its trial points; the converged row with the smallest error, or -1.
inline int64_t lm_step(const double* T, const double* J, LMState& S, const LMProblem& P) {
    int64_t best = -1;
    double best_f = INFINITY;
    for (int64_t k = 0; k < S.K; ++k)
        if (lm_row(k, T + 16 * k, J + 6 * S.nq * k, S, P) && S.fa[k] < best_f) best = k, best_f = S.fa[k];
    return best;
}

// lm.py lm_run: iterations with restarts until a row converges (its docstring states the
// contract). starts (M, nq); best_q (nq,), best_f (1,) updated; T (K, 4, 4), J (K, 6, nq) work.
// Returns the converged row or -1; evals and cursor updated.
inline int64_t lm_run(Kinematics& kin, int64_t anchor, const double* ER, const double* Ep, const bool* on_path,
                      const double* starts, int64_t M, int64_t n_starts, uint64_t gen_seed, int64_t& cursor,
                      int64_t max_evals, int64_t& evals, LMState& S, const LMProblem& P, double lam0, double* best_q,
                      double* best_f, double* T, double* J) {
    const int64_t K = S.K, nq = S.nq;
    evals = 0;
    while (true) {
        for (int64_t k = 0; k < K; ++k) {  // restart stalled rows from the next start
            if (S.status[k] != LM_STALLED) continue;
            if (S.fa[k] < best_f[0] && (P.project || into_limits(S.Qa + k * nq, P, nq))) {
                best_f[0] = S.fa[k];  // the best point within the limits (free iterates may be outside)
                for (int64_t j = 0; j < nq; ++j) best_q[j] = S.Qa[k * nq + j];
                S.fa[k] = INFINITY;  // counted once
            }
            if (cursor >= n_starts || evals + K > max_evals) return -1;
            double* Qt = S.Qt + k * nq;
            if (cursor < M) {
                for (int64_t j = 0; j < nq; ++j) Qt[j] = starts[cursor * nq + j];
            } else {  // uniform within the limits, from the counter-based generator
                for (int64_t j = 0; j < nq; ++j)
                    Qt[j] = P.lower[j] + (P.upper[j] - P.lower[j]) * uniform_at(gen_seed, (uint64_t)(cursor * nq + j));
            }
            ++cursor;
            S.fresh[k] = true, S.iters[k] = 0, S.stall[k] = 0, S.lam[k] = lam0, S.fa[k] = INFINITY;
            S.status[k] = LM_RUNNING;
        }
        if (evals + K > max_evals) return -1;
        int64_t best = -1;
        double best_fk = INFINITY;
        for (int64_t k = 0; k < K; ++k) {
            double* Tk = T + 16 * k;
            double* Jk = J + 6 * nq * k;
            if (!kin.fk_jacobian_one(S.Qt + k * nq, 1, anchor, ER, Ep, on_path, Tk, Jk)) {
                for (int i = 0; i < 16; ++i) Tk[i] = NAN;  // a non-finite trial point: the row stalls
            }
            ++evals;
            const bool conv = lm_row(k, Tk, Jk, S, P);
            for (int64_t j = 0; j < nq; ++j) S.Qt[k * nq + j] = S.Qn[k * nq + j];
            if (conv && S.fa[k] < best_fk) best = k, best_fk = S.fa[k];
        }
        if (best >= 0) return best;
    }
}

}  // namespace dmh
