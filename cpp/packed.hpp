// The arrays of the collision kernels, read from the two buffers of
// drake_mh/scene/kernels/packing.py (pack / _offsets): one of int64, one of float64. The layout
// here must follow _offsets there line by line.
#pragma once

#include <cstdint>
#include <memory>

#include "kinematics.hpp"

namespace dmh {

// The two buffers of pack, borrowed: their owner (the arrays they live in) is kept alive by
// `owner` as long as a model holds them; nothing writes them (a new scene packs new buffers). A
// new scene's models then share one copy (of the robot's pair tables too, about 1.2 MB for the
// Panda with its hand) instead of each copying it into fresh memory.
struct Buffers {
    const int64_t* ints = nullptr;
    int64_t n_ints = 0;
    const double* floats = nullptr;
    int64_t n_floats = 0;
    std::shared_ptr<const void> owner;
};

constexpr int64_t GRID_COLUMNS = 5;  // drake_mh.scene.pair_table.GRID_COLUMNS

struct Packed {
    Chain chain;
    int64_t G = 0, S = 0, K = 0, P = 0, T = 0, U = 0, D = 0;  // D >= K: rows of dims (mesh pieces' data after the obstacles')
    const int64_t *g_anchor, *g_start, *kinds, *pair_a, *pair_b, *t_meta, *g_ustart, *u_start;
    const double *g_offset, *g_radius, *s_offset, *s_radius, *R_WO, *p_WO, *dims, *o_radius, *o_gap, *t_grid,
        *t_vals, *g_capsule, *u_offset, *u_radius;
};

// Views into ints (n_ints,) and floats (n_floats,); false if the sizes do not match the header.
inline bool unpack(const int64_t* ints, int64_t n_ints, const double* floats, int64_t n_floats, Packed& s) {
    if (n_ints < 8) return false;
    const int64_t F = ints[0], G = ints[1], S = ints[2], K = ints[3], P = ints[4], T = ints[5], U = ints[6],
                  D = ints[7];
    if (F < 0 || G < 0 || S < 0 || K < 0 || P < 0 || T < 0 || U < 0 || D < K) return false;
    const int64_t i_parent = 8, i_perm = i_parent + F, i_kind = i_perm + 3 * F, i_qidx = i_kind + F,
                  i_anchor = i_qidx + F, i_start = i_anchor + G, i_kinds = i_start + G + 1, i_a = i_kinds + K,
                  i_b = i_a + P, i_meta = i_b + P, i_ustart = i_meta + 6 * P, i_ustart_s = i_ustart + G + 1,
                  i_end = i_ustart_s + U + 1;
    const int64_t f_KR = 0, f_Kp = f_KR + 9 * F, f_offset = f_Kp + 3 * F, f_radius = f_offset + 3 * G,
                  f_soffset = f_radius + G, f_sradius = f_soffset + 3 * S, f_RWO = f_sradius + S,
                  f_pWO = f_RWO + 9 * K, f_dims = f_pWO + 3 * K, f_orad = f_dims + 3 * D, f_ogap = f_orad + K,
                  f_grid = f_ogap + G * K, f_vals = f_grid + GRID_COLUMNS * P, f_caps = f_vals + T,
                  f_uoffset = f_caps + 7 * G, f_uradius = f_uoffset + 3 * U, f_end = f_uradius + U;
    if (i_end != n_ints || f_end != n_floats) return false;
    s.chain = Chain{F, ints + i_parent, floats + f_KR, floats + f_Kp, ints + i_perm, ints + i_kind, ints + i_qidx};
    s.G = G, s.S = S, s.K = K, s.P = P, s.T = T, s.U = U, s.D = D;
    s.g_anchor = ints + i_anchor, s.g_start = ints + i_start, s.kinds = ints + i_kinds, s.pair_a = ints + i_a;
    s.pair_b = ints + i_b, s.t_meta = ints + i_meta, s.g_ustart = ints + i_ustart, s.u_start = ints + i_ustart_s;
    s.g_offset = floats + f_offset, s.g_radius = floats + f_radius, s.s_offset = floats + f_soffset;
    s.s_radius = floats + f_sradius, s.R_WO = floats + f_RWO, s.p_WO = floats + f_pWO, s.dims = floats + f_dims;
    s.o_radius = floats + f_orad, s.o_gap = floats + f_ogap, s.t_grid = floats + f_grid, s.t_vals = floats + f_vals;
    s.g_capsule = floats + f_caps, s.u_offset = floats + f_uoffset, s.u_radius = floats + f_uradius;
    return true;
}

}  // namespace dmh
