// Clearance values of the sphere model: drake_mh/scene/kernels/collision.py link_clearances and
// its helpers (_obstacle_sd, _cloud_sd, _spheres_sd, _groups_sd), the same operations in the same
// order, so the same values up to round-off. Per link (and checked link pair), per obstacle or
// over all obstacles; obstacles may move: at lane parameter tau obstacle k is at
// p_WO[k] + tau v_WO[k] (v_WO passed per call).
//
// Layout as the numba kernel: a block of LANES configurations, lane index innermost (R (F, 3, 3,
// L), p (F, 3, L), bounding centres (G, L)); the lanes that need a link's spheres are compacted
// (gather) and each sphere is evaluated over them in plain loops over the lanes (left to the
// compiler's vectorizer, as numba leaves them to LLVM's).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "collision.hpp"

namespace dmh {

constexpr int PER_LINK = 0, PER_OBSTACLE = 1, OVERALL = 2;  // collision.py PER_LINK, PER_OBSTACLE, OVERALL

// out[i] = signed distance of point c[i] to obstacle k at parameter tau[i] (_obstacle_sd).
inline void obstacle_sd(const Packed& s, int64_t m, int64_t k, const double* v_WO, const double* __restrict tau,
                        const double* __restrict cx, const double* __restrict cy, const double* __restrict cz,
                        double* __restrict out) {
    const int64_t kind = s.kinds[k];
    const double px = s.p_WO[3 * k], py = s.p_WO[3 * k + 1], pz = s.p_WO[3 * k + 2];
    const double vx = v_WO[3 * k], vy = v_WO[3 * k + 1], vz = v_WO[3 * k + 2];
    const double* Rw = s.R_WO + 9 * k;
    const double r00 = Rw[0], r01 = Rw[1], r02 = Rw[2], r10 = Rw[3], r11 = Rw[4], r12 = Rw[5], r20 = Rw[6],
                 r21 = Rw[7], r22 = Rw[8];
    const double d0 = s.dims[3 * k], d1 = s.dims[3 * k + 1], d2 = s.dims[3 * k + 2];
    if (kind == SPHERE) {
        for (int64_t b = 0; b < m; ++b) {
            const double dx = cx[b] - px - vx * tau[b], dy = cy[b] - py - vy * tau[b], dz = cz[b] - pz - vz * tau[b];
            out[b] = std::sqrt(dx * dx + dy * dy + dz * dz) - d0;
        }
    } else if (kind == BOX) {
        for (int64_t b = 0; b < m; ++b) {
            const double dx = cx[b] - px - vx * tau[b], dy = cy[b] - py - vy * tau[b], dz = cz[b] - pz - vz * tau[b];
            const double qx = std::fabs(r00 * dx + r10 * dy + r20 * dz) - d0;
            const double qy = std::fabs(r01 * dx + r11 * dy + r21 * dz) - d1;
            const double qz = std::fabs(r02 * dx + r12 * dy + r22 * dz) - d2;
            const double ox = smax(qx, 0.0), oy = smax(qy, 0.0), oz = smax(qz, 0.0);
            out[b] = std::sqrt(ox * ox + oy * oy + oz * oz) + smin(smax(qx, smax(qy, qz)), 0.0);
        }
    } else if (kind == CYLINDER) {
        for (int64_t b = 0; b < m; ++b) {
            const double dx = cx[b] - px - vx * tau[b], dy = cy[b] - py - vy * tau[b], dz = cz[b] - pz - vz * tau[b];
            const double x = r00 * dx + r10 * dy + r20 * dz, y = r01 * dx + r11 * dy + r21 * dz,
                         z = r02 * dx + r12 * dy + r22 * dz;
            const double qr = std::sqrt(x * x + y * y) - d0, qa = std::fabs(z) - d1;
            const double orr = smax(qr, 0.0), oa = smax(qa, 0.0);
            out[b] = std::sqrt(orr * orr + oa * oa) + smin(smax(qr, qa), 0.0);
        }
    } else if (kind == CAPSULE) {
        for (int64_t b = 0; b < m; ++b) {
            const double dx = cx[b] - px - vx * tau[b], dy = cy[b] - py - vy * tau[b], dz = cz[b] - pz - vz * tau[b];
            const double x = r00 * dx + r10 * dy + r20 * dz, y = r01 * dx + r11 * dy + r21 * dz;
            double z = r02 * dx + r12 * dy + r22 * dz;
            z = z - smin(smax(z, -d1), d1);
            out[b] = std::sqrt(x * x + y * y + z * z) - d0;
        }
    } else if (kind == CONVEX) {
        for (int64_t b = 0; b < m; ++b)
            out[b] = convex_value(s, k, cx[b] - px - vx * tau[b], cy[b] - py - vy * tau[b], cz[b] - pz - vz * tau[b]);
    } else {  // CLOUD (points in W)
        const double rho = cloud_radius(s, k);
        for (int64_t b = 0; b < m; ++b)
            out[b] = std::sqrt(cloud_nearest2(s, k, cx[b] - vx * tau[b], cy[b] - vy * tau[b], cz[b] - vz * tau[b], INF)) -
                     rho;
    }
}

// sd[i]: the signed distance of point c[i] to cloud k (at tc[i]) where it is below cap[i] + grow,
// else a lower bound of it at least that (_cloud_sd). cap may be sd itself.
inline void cloud_sd(const Packed& s, int64_t c, int64_t k, const double* v_WO, const double* tc, const double* ccx,
                     const double* ccy, const double* ccz, const double* cap, double grow, double* sd) {
    const double rho = cloud_radius(s, k);
    const double vx = v_WO[3 * k], vy = v_WO[3 * k + 1], vz = v_WO[3 * k + 2];
    for (int64_t i = 0; i < c; ++i) {
        const double reach = cap[i] + grow + rho;
        if (reach <= 0.0) {
            sd[i] = -rho;
            continue;
        }
        const double bound2 = reach < INF ? reach * reach : INF;
        sd[i] = std::sqrt(cloud_nearest2(s, k, ccx[i] - vx * tc[i], ccy[i] - vy * tc[i], ccz[i] - vz * tc[i], bound2)) -
                rho;
    }
}

class Clearances : public PackedModel {
public:
    std::mutex busy;  // held by a call: the workspace is the object's own
    static constexpr int64_t LANES = 128;

    explicit Clearances(Buffers buffers) : PackedModel(std::move(buffers)) {
        if (!ok_) return;
        const int64_t F = std::max<int64_t>(s_.chain.F, 1), G = std::max<int64_t>(s_.G, 1),
                      K = std::max<int64_t>(s_.K, 1), L = LANES;
        U_ = 1;
        for (int64_t g = 0; g < s_.G; ++g) U_ = std::max(U_, s_.g_ustart[g + 1] - s_.g_ustart[g]);
        q_.resize(std::max<int64_t>(nq_, 1) * L);
        R_.resize(F * 9 * L), p_.resize(F * 3 * L), Gc_.resize(3 * G * L), lb_.resize(G * K * L);
        best_.resize(std::max(G, K) * L), lanes_.resize(12 * L), glb_.resize(U_ * L), Rc_.resize(9 * L);
        pbuf_.resize(4 * std::max<int64_t>(s_.S, 1));
        idx_.resize(L), key_.resize(U_), order_.resize(U_);
        bound_.resize(5 * G * L), pack_.resize(5 * PACKED);
    }

    // out (N, width) row-major, width = G + P (PER_LINK), K (PER_OBSTACLE) or 1 (OVERALL): the
    // values of link_clearances for Q (N, nq) row-major at tau (N,), obstacles displaced by v_WO
    // (K, 3) per unit of tau; fine_below and pair_fine (P,) as there (PER_LINK), or pair_fine (N, P)
    // one row per configuration with per_configuration. Q must be finite.
    void evaluate(const double* Q, int64_t N, const double* tau, double fine_below, const double* pair_fine, int mode,
                  const double* v_WO, double* out, bool per_configuration = false) {
        for (int64_t n0 = 0; n0 < N; n0 += LANES)
            block(Q, n0, std::min(LANES, N - n0), tau, fine_below, pair_fine, mode, v_WO, out, per_configuration);
    }

    int64_t width(int mode) const { return mode == OVERALL ? 1 : mode == PER_OBSTACLE ? s_.K : s_.G + s_.P; }

private:
    int64_t U_ = 1;  // most sphere groups of a link
    static constexpr int64_t PACKED = 512;  // points per packed obstacle_sd call of spheres_sd
    Buffer q_, R_, p_, Gc_, lb_, best_, lanes_, glb_, pbuf_, Rc_, bound_, pack_;
    std::vector<int64_t> idx_, order_;
    std::vector<double> key_;

    // Pose of moving frame a for the c lanes listed in idx, compacted: Rc (3, 3, L), pc (3, L).
    void gather(int64_t c, int64_t a, const double* R, const double* p, double* Rc, double* pc) const {
        const int64_t L = LANES;
        const int64_t* idx = idx_.data();
        for (int64_t i = 0; i < c; ++i) {
            const int64_t b = idx[i];
            for (int u = 0; u < 3; ++u) {
                pc[u * L + i] = a >= 0 ? p[(a * 3 + u) * L + b] : 0.0;
                for (int v = 0; v < 3; ++v)
                    Rc[(u * 3 + v) * L + i] = a >= 0 ? R[((a * 3 + u) * 3 + v) * L + b] : (u == v ? 1.0 : 0.0);
            }
        }
    }

    // World position of offset o (3,) for the c compacted lanes of pose (Rc, pc).
    static void compact_centres(int64_t c, const double* o, const double* __restrict Rc, const double* __restrict pc,
                                double* __restrict x, double* __restrict y, double* __restrict z) {
        const int64_t L = LANES;
        const double o0 = o[0], o1 = o[1], o2 = o[2];
        for (int64_t i = 0; i < c; ++i) {
            x[i] = pc[i] + Rc[i] * o0 + Rc[L + i] * o1 + Rc[2 * L + i] * o2;
            y[i] = pc[L + i] + Rc[3 * L + i] * o0 + Rc[4 * L + i] * o1 + Rc[5 * L + i] * o2;
            z[i] = pc[2 * L + i] + Rc[6 * L + i] * o0 + Rc[7 * L + i] * o1 + Rc[8 * L + i] * o2;
        }
    }

    // sc[i] = min(sc[i], sd_k(c_s) - r_s) over spheres s0 .. s1-1 of the compacted lanes (_spheres_sd).
    void spheres_sd(int64_t c, int64_t s0, int64_t s1, int64_t k, const double* v_WO, const double* tc,
                    const double* Rc, const double* pc, double* ccx, double* ccy, double* ccz, double* sd, double* sc,
                    const double* lim) {
        const bool cloud = s_.kinds[k] == CLOUD;
        if (!cloud) {  // several spheres' centres packed per call (a small block pays per call, not per point)
            const int64_t chunk = std::max<int64_t>(1, PACKED / std::max<int64_t>(c, 1));
            double *X = pack_.ptr, *Y = X + PACKED, *Z = Y + PACKED, *T = Z + PACKED, *S = T + PACKED;
            for (int64_t a = s0; a < s1; a += chunk) {
                const int64_t b = std::min(s1, a + chunk), n = (b - a) * c;
                for (int64_t si = a; si < b; ++si) {
                    const int64_t o = (si - a) * c;
                    compact_centres(c, s_.s_offset + 3 * si, Rc, pc, X + o, Y + o, Z + o);
                    std::copy_n(tc, c, T + o);
                }
                obstacle_sd(s_, n, k, v_WO, T, X, Y, Z, S);
                for (int64_t si = a; si < b; ++si) {
                    const double r = s_.s_radius[si];
                    const double* Si = S + (si - a) * c;
                    for (int64_t i = 0; i < c; ++i) sc[i] = smin(sc[i], Si[i] - r);
                }
            }
            return;
        }
        for (int64_t si = s0; si < s1; ++si) {
            compact_centres(c, s_.s_offset + 3 * si, Rc, pc, ccx, ccy, ccz);
            if (cloud) {
                for (int64_t i = 0; i < c; ++i) sd[i] = smin(sc[i], lim[i]);  // a point nearer lowers sc[i]
                cloud_sd(s_, c, k, v_WO, tc, ccx, ccy, ccz, sd, s_.s_radius[si], sd);
            } else {
                obstacle_sd(s_, c, k, v_WO, tc, ccx, ccy, ccz, sd);
            }
            const double r = s_.s_radius[si];
            for (int64_t i = 0; i < c; ++i) sc[i] = smin(sc[i], sd[i] - r);
        }
    }

    // spheres_sd over the groups u0 .. u1-1, the nearest (by bounding sphere) first; a group whose
    // bound is at least min(sc, lim) in every lane is skipped, its bound kept (_groups_sd).
    void groups_sd(int64_t c, int64_t u0, int64_t u1, const double* lim, int64_t k, const double* v_WO,
                   const double* tc, const double* Rc, const double* pc, double* ccx, double* ccy, double* ccz,
                   double* sd, double* sc, double* fl) {
        const int64_t L = LANES, nu = u1 - u0;
        double* glb = glb_.ptr;
        double* key = key_.data();
        int64_t* order = order_.data();
        const bool cloud = s_.kinds[k] == CLOUD;
        const int64_t chunk = cloud ? 1 : std::max<int64_t>(1, PACKED / std::max<int64_t>(c, 1));
        double *X = pack_.ptr, *Y = X + PACKED, *Z = Y + PACKED, *T = Z + PACKED, *S = T + PACKED;
        for (int64_t j0 = 0; j0 < nu; j0 += chunk) {  // the groups' centres packed per call (spheres_sd)
            const int64_t j1 = std::min(nu, j0 + chunk);
            if (!cloud) {
                for (int64_t j = j0; j < j1; ++j) {
                    const int64_t o = (j - j0) * c;
                    compact_centres(c, s_.u_offset + 3 * (u0 + j), Rc, pc, X + o, Y + o, Z + o);
                    std::copy_n(tc, c, T + o);
                }
                obstacle_sd(s_, (j1 - j0) * c, k, v_WO, T, X, Y, Z, S);
            }
            for (int64_t j = j0; j < j1; ++j) {
                const double* sj = S + (j - j0) * c;
                if (cloud) {
                    compact_centres(c, s_.u_offset + 3 * (u0 + j), Rc, pc, ccx, ccy, ccz);
                    cloud_sd(s_, c, k, v_WO, tc, ccx, ccy, ccz, lim, s_.u_radius[u0 + j], sd);
                    sj = sd;
                }
                double lowest = INF;
                const double r = s_.u_radius[u0 + j];
                for (int64_t i = 0; i < c; ++i) {
                    glb[j * L + i] = sj[i] - r;
                    lowest = smin(lowest, glb[j * L + i]);
                }
                key[j] = lowest;
            }
        }
        for (int64_t j = 0; j < nu; ++j) {  // insertion sort, stable: numba's argsort of so few keys
            int64_t i = j;
            while (i > 0 && key[j] < key[order[i - 1]]) {
                order[i] = order[i - 1];
                --i;
            }
            order[i] = j;
        }
        for (int64_t i = 0; i < c; ++i) fl[i] = INF;
        for (int64_t r = 0; r < nu; ++r) {
            const int64_t j = order[r];
            const double* gj = glb + j * L;
            bool need = false;
            for (int64_t i = 0; i < c; ++i) need |= gj[i] < smin(sc[i], lim[i]);
            if (need) {
                const int64_t u = u0 + j;
                spheres_sd(c, s_.u_start[u], s_.u_start[u + 1], k, v_WO, tc, Rc, pc, ccx, ccy, ccz, sd, sc, lim);
            } else {
                for (int64_t i = 0; i < c; ++i) fl[i] = smin(fl[i], gj[i]);
            }
        }
        for (int64_t i = 0; i < c; ++i) sc[i] = smin(sc[i], fl[i]);
    }

    void block(const double* Q, int64_t n0, int64_t m, const double* tau, double fine_below, const double* pair_fine,
               int mode, const double* v_WO, double* out, bool per_configuration) {
        const int64_t L = LANES, G = s_.G, K = s_.K, P = s_.P, nq = nq_, nv = (m + W - 1) / W;
        const bool per_obstacle = mode != PER_LINK, overall = mode == OVERALL;
        const int64_t width = this->width(mode);
        double* q = q_.ptr;
        for (int64_t j = 0; j < nq; ++j) {  // transposed: coordinate first, lanes past m zero
            double* row = q + j * L;
            for (int64_t b = 0; b < m; ++b) row[b] = Q[(n0 + b) * nq + j];
            for (int64_t b = m; b < nv * W; ++b) row[b] = 0.0;
        }
        double *R = R_.ptr, *p = p_.ptr, *Gx = Gc_.ptr, *Gy = Gx + G * L, *Gz = Gy + G * L, *lb = lb_.ptr,
               *best = best_.ptr;
        double *tb = lanes_.ptr, *sd = tb + L, *lim = sd + L, *tc = lim + L, *sc = tc + L, *fl = sc + L,
               *ccx = fl + L, *ccy = ccx + L, *ccz = ccy + L, *pc = ccz + L;  // pc (3, L) ends the 12 rows
        double* Rc = Rc_.ptr;  // (3, 3, L): the compacted lanes' pose
        int64_t* idx = idx_.data();
        for (int64_t b = 0; b < m; ++b) tb[b] = tau[n0 + b];
        frames_block(s_.chain, q, L, nv, R, p);
        // bounding spheres: a lower bound per link and obstacle; every link's centres of the m lanes
        // packed (G m) for one call per obstacle (a small block pays per call, not per point)
        const int64_t Gm = G * m;
        double *bx = bound_.ptr, *by = bx + Gm, *bz = by + Gm, *bt = bz + Gm, *bs = bt + Gm;
        for (int64_t g = 0; g < G; ++g) {
            double *cx = Gx + g * L, *cy = Gy + g * L, *cz = Gz + g * L;
            for (int64_t b = 0; b < m; ++b) {
                lane_point(s_.g_anchor[g], s_.g_offset + 3 * g, R, p, L, b, cx[b], cy[b], cz[b]);
                bx[g * m + b] = cx[b], by[g * m + b] = cy[b], bz[g * m + b] = cz[b], bt[g * m + b] = tb[b];
            }
        }
        for (int64_t k = 0; k < K; ++k) {
            if (s_.kinds[k] == CLOUD && !per_obstacle) {  // per link, exact below fine_below only
                for (int64_t b = 0; b < m; ++b) lim[b] = fine_below;
                for (int64_t g = 0; g < G; ++g) {
                    cloud_sd(s_, m, k, v_WO, tb, Gx + g * L, Gy + g * L, Gz + g * L, lim, s_.g_radius[g], sd);
                    double* l = lb + (g * K + k) * L;
                    for (int64_t b = 0; b < m; ++b) l[b] = sd[b] - s_.g_radius[g];
                }
                continue;
            }
            // per obstacle, exact: lb + 2 radius bounds the minimum from above
            obstacle_sd(s_, Gm, k, v_WO, bt, bx, by, bz, bs);
            for (int64_t g = 0; g < G; ++g) {
                double* l = lb + (g * K + k) * L;
                const double rg = s_.g_radius[g];
                for (int64_t b = 0; b < m; ++b) l[b] = bs[g * m + b] - rg;
            }
        }
        const int64_t rows_best = std::max<int64_t>(std::max(K, G), 1);
        for (int64_t r = 0; r < rows_best; ++r)
            for (int64_t b = 0; b < m; ++b) best[r * L + b] = INF;
        if (per_obstacle) {
            for (int64_t k = 0; k < K; ++k) {
                double* bk = best + (overall ? 0 : k) * L;
                for (int64_t g = 0; g < G; ++g) {
                    const double* l = lb + (g * K + k) * L;
                    const double two = 2.0 * s_.g_radius[g];
                    for (int64_t b = 0; b < m; ++b) bk[b] = smin(bk[b], l[b] + two);
                }
            }
        }
        for (int64_t g = 0; g < G; ++g) {
            const int64_t a = s_.g_anchor[g];
            double* bg = best + g * L;
            for (int64_t k = 0; k < K; ++k) {
                double* bk = best + (overall ? 0 : k) * L;  // the row of best that obstacle k lowers
                const double* l = lb + (g * K + k) * L;
                int64_t c = 0;
                for (int64_t b = 0; b < m; ++b)
                    if (l[b] < (per_obstacle ? bk[b] : fine_below)) idx[c++] = b;
                if (c == 0) {
                    if (!per_obstacle)
                        for (int64_t b = 0; b < m; ++b) bg[b] = smin(bg[b], l[b]);
                    continue;
                }
                gather(c, a, R, p, Rc, pc);
                for (int64_t i = 0; i < c; ++i) {
                    tc[i] = tb[idx[i]];
                    sc[i] = INF;
                    lim[i] = per_obstacle ? bk[idx[i]] : fine_below;  // per obstacle: the smallest value so far
                }
                if (s_.g_ustart[g + 1] - s_.g_ustart[g] > 1)  // a group at a time, nearest first
                    groups_sd(c, s_.g_ustart[g], s_.g_ustart[g + 1], lim, k, v_WO, tc, Rc, pc, ccx, ccy, ccz, sd, sc,
                              fl);
                else
                    spheres_sd(c, s_.g_start[g], s_.g_start[g + 1], k, v_WO, tc, Rc, pc, ccx, ccy, ccz, sd, sc, lim);
                if (per_obstacle) {
                    for (int64_t i = 0; i < c; ++i) bk[idx[i]] = smin(bk[idx[i]], sc[i]);
                } else {
                    for (int64_t b = 0; b < m; ++b)  // lanes not listed keep the lower bound
                        bg[b] = l[b] >= fine_below ? smin(bg[b], l[b]) : bg[b];
                    for (int64_t i = 0; i < c; ++i) bg[idx[i]] = smin(bg[idx[i]], sc[i]);
                }
            }
        }
        const int64_t rows = overall ? 1 : per_obstacle ? K : G;
        for (int64_t r = 0; r < rows; ++r)
            for (int64_t b = 0; b < m; ++b) out[(n0 + b) * width + r] = best[r * L + b];
        if (per_obstacle) return;
        for (int64_t i = 0; i < P; ++i) {
            const int64_t ga = s_.pair_a[i], gb = s_.pair_b[i];
            for (int64_t b = 0; b < m; ++b) {
                const double fine = per_configuration ? pair_fine[(n0 + b) * P + i] : pair_fine[i];
                const double dx = Gx[ga * L + b] - Gx[gb * L + b], dy = Gy[ga * L + b] - Gy[gb * L + b],
                             dz = Gz[ga * L + b] - Gz[gb * L + b];
                double v = std::sqrt(dx * dx + dy * dy + dz * dz) - s_.g_radius[ga] - s_.g_radius[gb];
                if (v < fine) v = smax(v, capsule_gap(s_, b, ga, gb, R, p, L));  // the bounding capsules' value
                if (v < fine) {  // exact below the pair's fine_below, a lower bound (at least v) above
                    const double floor = pair_floor(s_, i, q + b, L);
                    if (floor >= fine) {  // the pair's table: a lower bound above fine
                        out[(n0 + b) * width + G + i] = smax(v, floor);
                        continue;
                    }
                    v = pair_clearance(s_, b, ga, gb, fine, -INF, true, Gx[ga * L + b], Gy[ga * L + b],
                                       Gz[ga * L + b], Gx[gb * L + b], Gy[gb * L + b], Gz[gb * L + b], R, p, L,
                                       pbuf_.ptr);
                }
                out[(n0 + b) * width + G + i] = v;
            }
        }
    }
};

}  // namespace dmh
