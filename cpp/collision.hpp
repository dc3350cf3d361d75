// The boolean sphere-model check of drake_mh/scene/kernels/collision.py (collision_free) and
// entry.py (_free_one): every sphere at least `clearance` from every obstacle and every checked
// link pair at least `self_clearance` apart. Same tests in the same order, so the same answers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "spheres.hpp"

namespace dmh {

// 64-byte aligned doubles, allocated once per model and reused by every call.
struct Buffer {
    std::vector<double> data;
    double* ptr = nullptr;
    void resize(size_t n) {
        data.assign(n + 8, 0.0);
        ptr = reinterpret_cast<double*>((reinterpret_cast<uintptr_t>(data.data()) + 63) & ~uintptr_t(63));
    }
};

// A model's packed buffers (copies, held for the object's life), their views, and whether they
// hold a model (sizes matching the header, known obstacle kinds).
class PackedModel {
public:
    explicit PackedModel(Buffers buffers) : buffers_(std::move(buffers)) {
        ok_ = unpack(buffers_.ints, buffers_.n_ints, buffers_.floats, buffers_.n_floats, s_);
        if (!ok_) return;
        for (int64_t k = 0; k < s_.K; ++k) ok_ = ok_ && s_.kinds[k] >= SPHERE && s_.kinds[k] <= CLOUD;
        for (int64_t k = 0; k < s_.chain.F; ++k) nq_ = std::max(nq_, s_.chain.qidx[k] + 1);
    }

    bool ok() const { return ok_; }
    int64_t nq() const { return nq_; }
    const Packed& packed() const { return s_; }

protected:
    Buffers buffers_;
    Packed s_;
    bool ok_ = false;
    int64_t nq_ = 0;
};

class CollisionChecker : public PackedModel {
public:
    std::mutex busy;  // held by a call: the workspace is the object's own
    static constexpr int64_t LANES = 128;  // configurations per block (a multiple of W)

    explicit CollisionChecker(Buffers buffers) : PackedModel(std::move(buffers)) {
        if (!ok_) return;
        const int64_t F = s_.chain.F, L = LANES;
        q_.resize(std::max<int64_t>(nq_, 1) * L);
        R_.resize(F * 9 * L);
        p_.resize(F * 3 * L);
        Gc_.resize(3 * std::max<int64_t>(s_.G, 1) * L);
        alive_.resize(L);
        pbuf_.resize(4 * std::max<int64_t>(s_.S, 1));
        R1_.resize(9 * std::max<int64_t>(F, 1));
        p1_.resize(3 * std::max<int64_t>(F, 1));
        gc1_.resize(3 * std::max<int64_t>(s_.G, 1));
    }

    // out[n] for the N configurations Q (N, nq) (row-major); false (nothing written) if Q holds
    // a NaN or an infinity. Clearances > 0 (the tests compare squares).
    bool free_batch(const double* Q, int64_t N, int64_t nq, double clearance, double self_clearance, bool* out) {
        for (int64_t i = 0; i < N * nq; ++i)
            if (!std::isfinite(Q[i])) return false;
        for (int64_t n0 = 0; n0 < N; n0 += LANES) block(Q, n0, std::min(LANES, N - n0), nq, clearance, self_clearance, out);
        return true;
    }

    // One configuration q (nq,) with stride qs (elements): 1 free, 0 not, -1 not finite, -2 a
    // clearance not in [0, inf) (entry.py collision_free_one).
    int free_one(const double* q, int64_t qs, double clearance, double self_clearance) {
        if (!(0.0 <= clearance && clearance < INF && 0.0 <= self_clearance && self_clearance < INF)) return -2;
        for (int64_t j = 0; j < nq_; ++j)
            if (!std::isfinite(q[j * qs])) return -1;
        clearance = std::max(clearance, 1e-12), self_clearance = std::max(self_clearance, 1e-12);
        return one(q, qs, clearance, self_clearance) ? 1 : 0;
    }

private:
    Buffer q_, R_, p_, Gc_, alive_, pbuf_, R1_, p1_, gc1_;

    void block(const double* Q, int64_t n0, int64_t m, int64_t nq, double clearance, double self_clearance,
               bool* out) {
        const int64_t L = LANES, G = s_.G, K = s_.K, nv = (m + W - 1) / W;
        double* q = q_.ptr;
        for (int64_t j = 0; j < nq; ++j) {  // transposed: coordinate first, lanes past m zero
            double* row = q + j * L;
            for (int64_t b = 0; b < m; ++b) row[b] = Q[(n0 + b) * nq + j];
            for (int64_t b = m; b < nv * W; ++b) row[b] = 0.0;
        }
        double *R = R_.ptr, *p = p_.ptr, *Gx = Gc_.ptr, *Gy = Gx + G * L, *Gz = Gy + G * L;
        vi* alive = reinterpret_cast<vi*>(alive_.ptr);
        frames_block(s_.chain, q, L, nv, R, p);
        for (int64_t v = 0; v < nv; ++v) {
            vi lane;
            for (int i = 0; i < W; ++i) lane[i] = v * W + i < m ? -1 : 0;
            alive[v] = lane;
        }
        for (int64_t g = 0; g < G; ++g) {
            const int64_t a = s_.g_anchor[g];
            const double* o = s_.g_offset + 3 * g;
            double *gx = Gx + g * L, *gy = Gy + g * L, *gz = Gz + g * L;
            centres_v(a, o, R, p, L, nv, gx, gy, gz);
            const double reach = clearance + s_.g_radius[g];
            const bool grouped = s_.g_ustart[g + 1] - s_.g_ustart[g] > 1;
            for (int64_t k = 0; k < K; ++k) {
                if (s_.o_gap[g * K + k] >= clearance) continue;  // no configuration brings them near
                if (!bounding_close(s_, g, k, clearance, gx, gy, gz, nv, alive)) continue;  // bounding spheres apart
                for (int64_t v = 0; v < nv; ++v) {  // the link's bounding sphere vs the obstacle's shape
                    const vi hit = alive[v] & ~obstacle_free_v(s_, k, reach, load(gx + v * W), load(gy + v * W),
                                                               load(gz + v * W), alive[v]);
                    if (!any(hit)) continue;
                    vi lane = alive[v];
                    for (int i = 0; i < W; ++i) {
                        if (!hit[i]) continue;
                        const int64_t b = v * W + i;
                        const bool free = grouped ? groups_free(s_, b, a, s_.g_ustart[g], s_.g_ustart[g + 1],
                                                                clearance, R, p, L, k)
                                                  : range_free(s_, b, a, s_.g_start[g], s_.g_start[g + 1],
                                                               clearance, R, p, L, k);
                        lane[i] = free ? -1 : 0;
                    }
                    alive[v] = lane;
                }
            }
            vi any_alive{};
            for (int64_t v = 0; v < nv; ++v) any_alive |= alive[v];
            if (!any(any_alive)) break;
        }
        for (int64_t i = 0; i < s_.P; ++i) {
            const int64_t ga = s_.pair_a[i], gb = s_.pair_b[i];
            double lim = self_clearance + s_.g_radius[ga] + s_.g_radius[gb];
            lim *= lim;
            for (int64_t v = 0; v < nv; ++v) {
                const int64_t o = v * W;
                const vd dx = load(Gx + ga * L + o) - load(Gx + gb * L + o);
                const vd dy = load(Gy + ga * L + o) - load(Gy + gb * L + o);
                const vd dz = load(Gz + ga * L + o) - load(Gz + gb * L + o);
                const vi near = alive[v] & (dx * dx + dy * dy + dz * dz < lim);
                if (!any(near)) continue;
                vi lane = alive[v];
                for (int j = 0; j < W; ++j) {
                    if (!near[j]) continue;
                    const int64_t b = o + j;
                    if (pair_floor(s_, i, q + b, L) >= self_clearance) continue;  // the pair's table
                    if (capsule_gap(s_, b, ga, gb, R, p, L) >= self_clearance) continue;  // the bounding capsules
                    const double value = pair_clearance(
                        s_, b, ga, gb, self_clearance, self_clearance, false, Gx[ga * L + b], Gy[ga * L + b],
                        Gz[ga * L + b], Gx[gb * L + b], Gy[gb * L + b], Gz[gb * L + b], R, p, L, pbuf_.ptr);
                    if (!(value >= self_clearance)) lane[j] = 0;
                }
                alive[v] = lane;
            }
        }
        for (int64_t b = 0; b < m; ++b) out[n0 + b] = alive[b / W][b % W] != 0;
    }

    bool one(const double* q, int64_t qs, double clearance, double self_clearance) {
        double *R = R1_.ptr, *p = p1_.ptr, *gc = gc1_.ptr;
        frames_one(s_.chain, q, qs, R, p);
        const int64_t G = s_.G, K = s_.K;
        for (int64_t g = 0; g < G; ++g) {
            const int64_t a = s_.g_anchor[g];
            double x, y, z;
            lane_point(a, s_.g_offset + 3 * g, R, p, 1, 0, x, y, z);
            gc[3 * g] = x, gc[3 * g + 1] = y, gc[3 * g + 2] = z;
            const double reach = clearance + s_.g_radius[g];
            for (int64_t k = 0; k < K; ++k) {
                if (s_.o_gap[g * K + k] >= clearance) continue;
                const double dx = x - s_.p_WO[3 * k], dy = y - s_.p_WO[3 * k + 1], dz = z - s_.p_WO[3 * k + 2];
                const double lim = reach + s_.o_radius[k];
                if (dx * dx + dy * dy + dz * dz >= lim * lim) continue;  // bounding spheres apart
                if (point_free(s_, k, reach, x, y, z)) continue;  // bounding sphere vs the shape
                if (s_.g_ustart[g + 1] - s_.g_ustart[g] > 1) {
                    if (!groups_free(s_, 0, a, s_.g_ustart[g], s_.g_ustart[g + 1], clearance, R, p, 1, k)) return false;
                } else if (!range_free(s_, 0, a, s_.g_start[g], s_.g_start[g + 1], clearance, R, p, 1, k)) {
                    return false;
                }
            }
        }
        for (int64_t i = 0; i < s_.P; ++i) {
            const int64_t ga = s_.pair_a[i], gb = s_.pair_b[i];
            const double *ca = gc + 3 * ga, *cb = gc + 3 * gb;
            const double dx = ca[0] - cb[0], dy = ca[1] - cb[1], dz = ca[2] - cb[2];
            const double lim = self_clearance + s_.g_radius[ga] + s_.g_radius[gb];
            if (dx * dx + dy * dy + dz * dz < lim * lim && pair_floor(s_, i, q, qs) < self_clearance &&
                capsule_gap(s_, 0, ga, gb, R, p, 1) < self_clearance &&
                pair_clearance(s_, 0, ga, gb, self_clearance, self_clearance, false, ca[0], ca[1], ca[2], cb[0],
                               cb[1], cb[2], R, p, 1, pbuf_.ptr) < self_clearance)
                return false;
        }
        return true;
    }
};

}  // namespace dmh
