// Prototype: the sphere model's batched collision_free (drake_mh.scene._collision_kernels.collision_free)
// in C++ through nanobind, on the same two packed buffers (drake_mh.scene._packing.pack), so that its
// install-time build, runtime and size can be set beside the numba kernel's. Obstacles only: a model
// with checked link pairs (P > 0) is refused.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace nb = nanobind;

namespace {

constexpr int LANES = 128;
constexpr int GRID_COLUMNS = 5;
enum { SPHERE = 0, BOX = 1, CYLINDER = 2, CAPSULE = 3 };

// fdlibm constants (drake_mh._kernels._sincos_block)
constexpr double INV_PIO2 = 6.36619772367581382433e-01, PIO2_1 = 1.57079632673412561417e00,
                 PIO2_2 = 6.07710050630396597660e-11, PIO2_3 = 2.02226624871116645580e-21;
constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03, S3 = -1.98412698298579493134e-04,
                 S4 = 2.75573137070700676789e-06, S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03, C3 = 2.48015872894767294178e-05,
                 C4 = -2.75573143513906633035e-07, C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
constexpr double LARGE = 1e5;

struct Model {  // views into the packed buffers (drake_mh.scene._packing._offsets)
  int64_t F, G, S, K, P, T, U;
  const int64_t *parent, *perm, *kind, *qidx, *g_anchor, *g_start, *kinds, *g_ustart, *u_start;
  const double *KR, *Kp, *g_offset, *g_radius, *s_offset, *s_radius, *R_WO, *p_WO, *dims, *o_radius, *o_gap,
      *u_offset, *u_radius;
};

Model unpack(const int64_t *ints, const double *floats) {
  Model m;
  m.F = ints[0]; m.G = ints[1]; m.S = ints[2]; m.K = ints[3]; m.P = ints[4]; m.T = ints[5]; m.U = ints[6];
  const int64_t *i = ints + 7;
  m.parent = i; i += m.F;
  m.perm = i; i += 3 * m.F;
  m.kind = i; i += m.F;
  m.qidx = i; i += m.F;
  m.g_anchor = i; i += m.G;
  m.g_start = i; i += m.G + 1;
  m.kinds = i; i += m.K;
  i += 2 * m.P + 6 * m.P;  // pair_a, pair_b, t_meta
  m.g_ustart = i; i += m.G + 1;
  m.u_start = i;
  const double *f = floats;
  m.KR = f; f += 9 * m.F;
  m.Kp = f; f += 3 * m.F;
  m.g_offset = f; f += 3 * m.G;
  m.g_radius = f; f += m.G;
  m.s_offset = f; f += 3 * m.S;
  m.s_radius = f; f += m.S;
  m.R_WO = f; f += 9 * m.K;
  m.p_WO = f; f += 3 * m.K;
  m.dims = f; f += 3 * m.K;
  m.o_radius = f; f += m.K;
  m.o_gap = f; f += m.G * m.K;
  f += GRID_COLUMNS * m.P + m.T + 7 * m.G;  // t_grid, t_vals, g_capsule
  m.u_offset = f; f += 3 * m.U;
  m.u_radius = f;
  return m;
}

// block work arrays, lane index innermost: R[k][i][j][b], p[k][i][b]
struct Block {
  std::vector<double> R, p;
  double sn[LANES], cs[LANES], cx[LANES], cy[LANES], cz[LANES];
  uint8_t alive[LANES], nearb[LANES];
  explicit Block(int64_t F) : R(F * 9 * LANES), p(F * 3 * LANES) {}
  double &r(int64_t k, int i, int j, int b) { return R[((k * 3 + i) * 3 + j) * LANES + b]; }
  double &q(int64_t k, int i, int b) { return p[(k * 3 + i) * LANES + b]; }
};

void sincos_block(const double *__restrict x, double *__restrict s_out, double *__restrict c_out, int m) {
  double largest = 0.0;
  for (int b = 0; b < m; ++b) {
    double xb = x[b];
    double nf = std::floor(xb * INV_PIO2 + 0.5);
    double r = ((xb - nf * PIO2_1) - nf * PIO2_2) - nf * PIO2_3;
    double z = r * r;
    double sp = r + r * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    double cp = 1.0 - 0.5 * z + z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    // the quadrant n mod 4 in doubles (exact: |nf| < 2^52; the vector loop needs no integer)
    double quad = nf - 4.0 * std::floor(nf * 0.25);
    bool odd = quad == 1.0 || quad == 3.0;
    double s = odd ? cp : sp, c = odd ? sp : cp;
    s_out[b] = quad >= 2.0 ? -s : s;
    c_out[b] = (quad == 1.0 || quad == 2.0) ? -c : c;
    largest = std::max(largest, std::fabs(xb));
  }
  if (largest > LARGE)
    for (int b = 0; b < m; ++b)
      if (std::fabs(x[b]) > LARGE) { s_out[b] = std::sin(x[b]); c_out[b] = std::cos(x[b]); }
}

// drake_mh._kernels._frames_block on QT (nq, N) row-major
void frames_block(const Model &M, const double *QT, int64_t N, int64_t n0, int m, Block &w) {
  for (int64_t k = 0; k < M.F; ++k) {
    int64_t a = M.parent[k];
    const double *row = QT + M.qidx[k] * N + n0;
    bool revolute = M.kind[k] == 0;
    const double *KR = M.KR + 9 * k, *Kp = M.Kp + 3 * k;
    const int64_t *perm = M.perm + 3 * k;
    if (revolute) sincos_block(row, w.sn, w.cs, m);
    if (a >= 0) {
      for (int i = 0; i < 3; ++i) {
        double *pk = &w.q(k, i, 0);
        const double *pa = &w.q(a, i, 0), *r0 = &w.r(a, i, 0, 0), *r1 = &w.r(a, i, 1, 0), *r2 = &w.r(a, i, 2, 0);
        for (int b = 0; b < m; ++b) pk[b] = pa[b] + r0[b] * Kp[0] + r1[b] * Kp[1] + r2[b] * Kp[2];
      }
    }
    if (a >= 0 && revolute && perm[0] >= 0) {
      int64_t s0 = perm[0], s1 = perm[1], s2 = perm[2];
      double g0 = KR[s0 * 3 + 0], g1 = KR[s1 * 3 + 1], g2 = KR[s2 * 3 + 2];
      for (int i = 0; i < 3; ++i) {
        const double *a0 = &w.r(a, i, s0, 0), *a1 = &w.r(a, i, s1, 0), *a2 = &w.r(a, i, s2, 0);
        double *k0 = &w.r(k, i, 0, 0), *k1 = &w.r(k, i, 1, 0), *k2 = &w.r(k, i, 2, 0);
        for (int b = 0; b < m; ++b) {
          double r0 = g0 * a0[b], r1 = g1 * a1[b];
          k2[b] = g2 * a2[b];
          k0[b] = r0 * w.cs[b] + r1 * w.sn[b];
          k1[b] = r1 * w.cs[b] - r0 * w.sn[b];
        }
      }
      continue;
    }
    if (a < 0) {
      for (int i = 0; i < 3; ++i) {
        for (int b = 0; b < m; ++b) w.q(k, i, b) = Kp[i];
        for (int j = 0; j < 3; ++j)
          for (int b = 0; b < m; ++b) w.r(k, i, j, b) = KR[i * 3 + j];
      }
    } else if (perm[0] >= 0) {
      for (int j = 0; j < 3; ++j) {
        int64_t src = perm[j];
        double sg = KR[src * 3 + j];
        for (int i = 0; i < 3; ++i)
          for (int b = 0; b < m; ++b) w.r(k, i, j, b) = sg * w.r(a, i, src, b);
      }
    } else {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          double k0 = KR[0 * 3 + j], k1 = KR[1 * 3 + j], k2 = KR[2 * 3 + j];
          for (int b = 0; b < m; ++b)
            w.r(k, i, j, b) = w.r(a, i, 0, b) * k0 + w.r(a, i, 1, b) * k1 + w.r(a, i, 2, b) * k2;
        }
    }
    if (revolute) {
      for (int i = 0; i < 3; ++i) {
        double *k0 = &w.r(k, i, 0, 0), *k1 = &w.r(k, i, 1, 0);
        for (int b = 0; b < m; ++b) {
          double r0 = k0[b], r1 = k1[b];
          k0[b] = r0 * w.cs[b] + r1 * w.sn[b];
          k1[b] = r1 * w.cs[b] - r0 * w.sn[b];
        }
      }
    } else {
      for (int i = 0; i < 3; ++i)
        for (int b = 0; b < m; ++b) w.q(k, i, b) += w.r(k, i, 2, b) * row[b];
    }
  }
}

inline void lane_point(Block &w, int64_t a, const double *o, int b, double &x, double &y, double &z) {
  if (a < 0) { x = o[0]; y = o[1]; z = o[2]; return; }
  x = w.q(a, 0, b) + w.r(a, 0, 0, b) * o[0] + w.r(a, 0, 1, b) * o[1] + w.r(a, 0, 2, b) * o[2];
  y = w.q(a, 1, b) + w.r(a, 1, 0, b) * o[0] + w.r(a, 1, 1, b) * o[1] + w.r(a, 1, 2, b) * o[2];
  z = w.q(a, 2, b) + w.r(a, 2, 0, b) * o[0] + w.r(a, 2, 1, b) * o[1] + w.r(a, 2, 2, b) * o[2];
}

inline bool point_free(const Model &M, int64_t k, double reach, double x, double y, double z) {
  const double *p = M.p_WO + 3 * k, *R = M.R_WO + 9 * k, *d = M.dims + 3 * k;
  double dx = x - p[0], dy = y - p[1], dz = z - p[2];
  int64_t kind = M.kinds[k];
  if (kind == SPHERE) return dx * dx + dy * dy + dz * dz >= (reach + d[0]) * (reach + d[0]);
  double u = R[0] * dx + R[3] * dy + R[6] * dz, v = R[1] * dx + R[4] * dy + R[7] * dz, t = R[2] * dx + R[5] * dy + R[8] * dz;
  if (kind == BOX) {
    double ox = std::max(std::fabs(u) - d[0], 0.0), oy = std::max(std::fabs(v) - d[1], 0.0),
           oz = std::max(std::fabs(t) - d[2], 0.0);
    return ox * ox + oy * oy + oz * oz >= reach * reach;
  }
  if (kind == CYLINDER) {
    double orr = std::max(std::sqrt(u * u + v * v) - d[0], 0.0), oa = std::max(std::fabs(t) - d[1], 0.0);
    return orr * orr + oa * oa >= reach * reach;
  }
  t = t - std::min(std::max(t, -d[1]), d[1]);
  return u * u + v * v + t * t >= (reach + d[0]) * (reach + d[0]);
}

// _obstacle_free: alive[b] &= point c[b] at least reach from obstacle k (lanes)
void obstacle_free(const Model &M, int m, int64_t k, double reach, Block &w, uint8_t *alive) {
  const double *p = M.p_WO + 3 * k, *R = M.R_WO + 9 * k, *d = M.dims + 3 * k;
  double px = p[0], py = p[1], pz = p[2];
  double r00 = R[0], r01 = R[1], r02 = R[2], r10 = R[3], r11 = R[4], r12 = R[5], r20 = R[6], r21 = R[7], r22 = R[8];
  double d0 = d[0], d1 = d[1], d2 = d[2];
  int64_t kind = M.kinds[k];
  const double *cx = w.cx, *cy = w.cy, *cz = w.cz;
  if (kind == SPHERE) {
    double lim = (reach + d0) * (reach + d0);
    for (int b = 0; b < m; ++b) {
      double dx = cx[b] - px, dy = cy[b] - py, dz = cz[b] - pz;
      alive[b] &= dx * dx + dy * dy + dz * dz >= lim;
    }
  } else if (kind == BOX) {
    double lim = reach * reach;
    for (int b = 0; b < m; ++b) {
      double dx = cx[b] - px, dy = cy[b] - py, dz = cz[b] - pz;
      double ox = std::max(std::fabs(r00 * dx + r10 * dy + r20 * dz) - d0, 0.0);
      double oy = std::max(std::fabs(r01 * dx + r11 * dy + r21 * dz) - d1, 0.0);
      double oz = std::max(std::fabs(r02 * dx + r12 * dy + r22 * dz) - d2, 0.0);
      alive[b] &= ox * ox + oy * oy + oz * oz >= lim;
    }
  } else if (kind == CYLINDER) {
    double lim = reach * reach;
    for (int b = 0; b < m; ++b) {
      double dx = cx[b] - px, dy = cy[b] - py, dz = cz[b] - pz;
      double x = r00 * dx + r10 * dy + r20 * dz, y = r01 * dx + r11 * dy + r21 * dz, z = r02 * dx + r12 * dy + r22 * dz;
      double orr = std::max(std::sqrt(x * x + y * y) - d0, 0.0), oa = std::max(std::fabs(z) - d1, 0.0);
      alive[b] &= orr * orr + oa * oa >= lim;
    }
  } else {
    double lim = (reach + d0) * (reach + d0);
    for (int b = 0; b < m; ++b) {
      double dx = cx[b] - px, dy = cy[b] - py, dz = cz[b] - pz;
      double x = r00 * dx + r10 * dy + r20 * dz, y = r01 * dx + r11 * dy + r21 * dz, z = r02 * dx + r12 * dy + r22 * dz;
      z = z - std::min(std::max(z, -d1), d1);
      alive[b] &= x * x + y * y + z * z >= lim;
    }
  }
}

bool range_free(const Model &M, Block &w, int b, int64_t a, int64_t s0, int64_t s1, double clearance, int64_t k) {
  for (int64_t s = s0; s < s1; ++s) {
    double x, y, z;
    lane_point(w, a, M.s_offset + 3 * s, b, x, y, z);
    if (!point_free(M, k, clearance + M.s_radius[s], x, y, z)) return false;
  }
  return true;
}

bool groups_free(const Model &M, Block &w, int b, int64_t a, int64_t u0, int64_t u1, double clearance, int64_t k) {
  for (int64_t u = u0; u < u1; ++u) {
    double x, y, z;
    lane_point(w, a, M.u_offset + 3 * u, b, x, y, z);
    if (!point_free(M, k, clearance + M.u_radius[u], x, y, z) &&
        !range_free(M, w, b, a, M.u_start[u], M.u_start[u + 1], clearance, k))
      return false;
  }
  return true;
}

// collision_free of QT (nq, N), obstacles only
void collision_free(const Model &M, const double *QT, int64_t N, double clearance, bool *out) {
  Block w(M.F);
  for (int64_t n0 = 0; n0 < N; n0 += LANES) {
    int m = (int)std::min<int64_t>(LANES, N - n0);
    frames_block(M, QT, N, n0, m, w);
    for (int b = 0; b < m; ++b) w.alive[b] = 1;
    for (int64_t g = 0; g < M.G; ++g) {
      int64_t a = M.g_anchor[g];
      const double *o = M.g_offset + 3 * g;
      if (a < 0) {
        for (int b = 0; b < m; ++b) { w.cx[b] = o[0]; w.cy[b] = o[1]; w.cz[b] = o[2]; }
      } else {
        for (int b = 0; b < m; ++b) {
          w.cx[b] = w.q(a, 0, b) + w.r(a, 0, 0, b) * o[0] + w.r(a, 0, 1, b) * o[1] + w.r(a, 0, 2, b) * o[2];
          w.cy[b] = w.q(a, 1, b) + w.r(a, 1, 0, b) * o[0] + w.r(a, 1, 1, b) * o[1] + w.r(a, 1, 2, b) * o[2];
          w.cz[b] = w.q(a, 2, b) + w.r(a, 2, 0, b) * o[0] + w.r(a, 2, 1, b) * o[1] + w.r(a, 2, 2, b) * o[2];
        }
      }
      for (int64_t k = 0; k < M.K; ++k) {
        if (M.o_gap[g * M.K + k] >= clearance) continue;
        double lim = clearance + M.g_radius[g] + M.o_radius[k];
        lim *= lim;
        const double *p = M.p_WO + 3 * k;
        bool close = false;
        for (int b = 0; b < m; ++b) {
          double dx = w.cx[b] - p[0], dy = w.cy[b] - p[1], dz = w.cz[b] - p[2];
          close |= dx * dx + dy * dy + dz * dz < lim;
        }
        if (!close) continue;
        for (int b = 0; b < m; ++b) w.nearb[b] = 1;
        obstacle_free(M, m, k, clearance + M.g_radius[g], w, w.nearb);
        for (int b = 0; b < m; ++b) {
          if (!(w.alive[b] && !w.nearb[b])) continue;
          if (M.g_ustart[g + 1] - M.g_ustart[g] > 1)
            w.alive[b] = groups_free(M, w, b, a, M.g_ustart[g], M.g_ustart[g + 1], clearance, k);
          else
            w.alive[b] = range_free(M, w, b, a, M.g_start[g], M.g_start[g + 1], clearance, k);
        }
      }
      bool any_alive = false;
      for (int b = 0; b < m; ++b) any_alive |= w.alive[b];
      if (!any_alive) break;
    }
    for (int b = 0; b < m; ++b) out[n0 + b] = w.alive[b];
  }
}

using QArray = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using IntBuf = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using FloatBuf = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using BoolOut = nb::ndarray<bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// collision_free_packed(Q (N, nq), clearance, self_clearance, ints, floats, out (N,)) -> False if Q not finite
bool collision_free_packed(QArray Q, double clearance, double self_clearance, IntBuf ints, FloatBuf floats,
                           BoolOut out) {
  Model M = unpack(ints.data(), floats.data());
  if (M.P != 0) throw std::invalid_argument("prototype: checked link pairs (P > 0) are not ported");
  int64_t N = (int64_t)Q.shape(0), nq = (int64_t)Q.shape(1);
  if ((int64_t)out.shape(0) != N) throw std::invalid_argument("out must have N entries");
  std::vector<double> QT(nq * N);
  const double *q = Q.data();
  for (int64_t n = 0; n < N; ++n)
    for (int64_t j = 0; j < nq; ++j) {
      double x = q[n * nq + j];
      if (!std::isfinite(x)) return false;
      QT[j * N + n] = x;
    }
  {
    nb::gil_scoped_release release;
    collision_free(M, QT.data(), N, clearance, out.data());
  }
  (void)self_clearance;
  return true;
}

}  // namespace

NB_MODULE(_collision_ext, m) {
  m.doc() = "Prototype: drake_mh's batched collision_free (obstacles only) in C++";
  m.def("collision_free_packed", &collision_free_packed, nb::arg("Q"), nb::arg("clearance"),
        nb::arg("self_clearance"), nb::arg("ints"), nb::arg("floats"), nb::arg("out"));
}
