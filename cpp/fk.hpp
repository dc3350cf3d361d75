// Batched forward kinematics and geometric Jacobians of a compiled chain: the answers of
// drake_mh/kinematics/kernels.py fk_jacobian and moving_frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "kinematics.hpp"

namespace dmh {

class Kinematics {
public:
    std::mutex busy;  // held by a call: the workspace is the object's own
    static constexpr int64_t BLOCK = 64;

    Kinematics(std::vector<int64_t> ints, std::vector<double> floats) : ints_(std::move(ints)), floats_(std::move(floats)) {
        const int64_t F = (int64_t)ints_.size() / 6;
        c_ = Chain{F, ints_.data(), floats_.data(), floats_.data() + 9 * F, ints_.data() + F, ints_.data() + 4 * F,
                   ints_.data() + 5 * F};
        nq_ = 0;
        for (int64_t k = 0; k < F; ++k) nq_ = std::max(nq_, c_.qidx[k] + 1);
        q_.assign(std::max<int64_t>(nq_, 1) * BLOCK, 0.0);
        R_.assign(F * 9 * BLOCK, 0.0);
        p_.assign(F * 3 * BLOCK, 0.0);
        R1_.assign(9 * std::max<int64_t>(F, 1), 0.0);
        p1_.assign(3 * std::max<int64_t>(F, 1), 0.0);
    }

    int64_t F() const { return c_.F; }
    int64_t nq() const { return nq_; }

    // Q (N, nq) row-major, finite. R_out (N, F, 3, 3), p_out (N, F, 3).
    void moving_frames(const double* Q, int64_t N, double* R_out, double* p_out) {
        const int64_t F = c_.F;
        for (int64_t n0 = 0; n0 < N; n0 += BLOCK) {
            const int64_t m = std::min(BLOCK, N - n0);
            run(Q, n0, m);
            for (int64_t b = 0; b < m; ++b)
                for (int64_t k = 0; k < F; ++k)
                    for (int i = 0; i < 3; ++i) {
                        p_out[((n0 + b) * F + k) * 3 + i] = p_[(k * 3 + i) * BLOCK + b];
                        for (int j = 0; j < 3; ++j)
                            R_out[(((n0 + b) * F + k) * 3 + i) * 3 + j] = R_[((k * 3 + i) * 3 + j) * BLOCK + b];
                    }
        }
    }

    // Pose T (N, 4, 4) of the frame fixed at (ER (3, 3), Ep (3,)) in moving frame `anchor`
    // (-1: the world) and, with J non-null, its Jacobians J (N, 6, nq), rows [w; v];
    // on_path (F,) marks the joints between the world and that frame.
    void fk_jacobian(const double* Q, int64_t N, int64_t anchor, const double* ER, const double* Ep,
                     const bool* on_path, double* T, double* J) {
        for (int64_t n0 = 0; n0 < N; n0 += BLOCK) {
            const int64_t m = std::min(BLOCK, N - n0);
            run(Q, n0, m);
            for (int64_t b = 0; b < m; ++b)
                pose_jacobian(R_.data(), p_.data(), BLOCK, b, anchor, ER, Ep, on_path, T + (n0 + b) * 16,
                              J ? J + (n0 + b) * 6 * nq_ : nullptr);
        }
    }

    // The same for one configuration q (nq,) read with stride qs; false (nothing written) if q is
    // not finite.
    bool fk_jacobian_one(const double* q, int64_t qs, int64_t anchor, const double* ER, const double* Ep,
                         const bool* on_path, double* T, double* J) {
        for (int64_t j = 0; j < nq_; ++j)
            if (!std::isfinite(q[j * qs])) return false;
        frames_one(c_, q, qs, R1_.data(), p1_.data());
        pose_jacobian(R1_.data(), p1_.data(), 1, 0, anchor, ER, Ep, on_path, T, J);
        return true;
    }

private:
    std::vector<int64_t> ints_;
    std::vector<double> floats_;
    Chain c_;
    int64_t nq_ = 0;
    std::vector<double> q_, R_, p_, R1_, p1_;

    // T (4, 4) and (J non-null) J (6, nq) of the frame at (ER, Ep) in moving frame anchor, from the
    // frames R (F, 3, 3, L), p (F, 3, L) of lane b.
    void pose_jacobian(const double* R, const double* p, int64_t L, int64_t b, int64_t anchor, const double* ER,
                       const double* Ep, const bool* on_path, double* Tn, double* Jn) const {
        const int64_t F = c_.F, nq = nq_;
        double Re[9], pe[3];
        for (int i = 0; i < 3; ++i) {
            if (anchor < 0) {
                pe[i] = Ep[i];
                for (int j = 0; j < 3; ++j) Re[i * 3 + j] = ER[i * 3 + j];
            } else {
                const double* Ra = R + (anchor * 9 + i * 3) * L + b;
                pe[i] = p[(anchor * 3 + i) * L + b] + Ra[0] * Ep[0] + Ra[L] * Ep[1] + Ra[2 * L] * Ep[2];
                for (int j = 0; j < 3; ++j) Re[i * 3 + j] = Ra[0] * ER[j] + Ra[L] * ER[3 + j] + Ra[2 * L] * ER[6 + j];
            }
        }
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) Tn[i * 4 + j] = Re[i * 3 + j];
            Tn[i * 4 + 3] = pe[i];
            Tn[12 + i] = 0.0;
        }
        Tn[15] = 1.0;
        if (!Jn) return;
        for (int64_t k = 0; k < F; ++k) {
            const int64_t col = c_.qidx[k];
            const double zx = R[((k * 3 + 0) * 3 + 2) * L + b], zy = R[((k * 3 + 1) * 3 + 2) * L + b],
                         zz = R[((k * 3 + 2) * 3 + 2) * L + b];
            if (!on_path[k]) {
                for (int i = 0; i < 6; ++i) Jn[i * nq + col] = 0.0;
            } else if (c_.kind[k] == 0) {
                const double dx = pe[0] - p[(k * 3 + 0) * L + b], dy = pe[1] - p[(k * 3 + 1) * L + b],
                             dz = pe[2] - p[(k * 3 + 2) * L + b];
                Jn[0 * nq + col] = zx, Jn[1 * nq + col] = zy, Jn[2 * nq + col] = zz;
                Jn[3 * nq + col] = zy * dz - zz * dy;
                Jn[4 * nq + col] = zz * dx - zx * dz;
                Jn[5 * nq + col] = zx * dy - zy * dx;
            } else {
                Jn[0 * nq + col] = 0.0, Jn[1 * nq + col] = 0.0, Jn[2 * nq + col] = 0.0;
                Jn[3 * nq + col] = zx, Jn[4 * nq + col] = zy, Jn[5 * nq + col] = zz;
            }
        }
    }

    void run(const double* Q, int64_t n0, int64_t m) {
        const int64_t nq = nq_, nv = (m + W - 1) / W;
        for (int64_t j = 0; j < nq; ++j) {
            double* row = q_.data() + j * BLOCK;
            for (int64_t b = 0; b < m; ++b) row[b] = Q[(n0 + b) * nq + j];
            for (int64_t b = m; b < nv * W; ++b) row[b] = 0.0;
        }
        frames_block(c_, q_.data(), BLOCK, nv, R_.data(), p_.data());
    }
};

}  // namespace dmh
