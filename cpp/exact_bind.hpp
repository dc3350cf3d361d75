// Bindings of the exact distances (exact.hpp) and the penetration correction (penetration.hpp):
// module functions with the arguments of their numba twins, so that a caller picks either.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <initializer_list>

#include "exact.hpp"
#include "penetration.hpp"

namespace dmh_bind {

namespace nb = nanobind;
using namespace nb::literals;

using In = nb::ndarray<const double, nb::c_contig, nb::device::cpu>;
using InI = nb::ndarray<const int64_t, nb::c_contig, nb::device::cpu>;
using Out = nb::ndarray<double, nb::c_contig, nb::device::cpu>;
using OutI = nb::ndarray<int64_t, nb::c_contig, nb::device::cpu>;

// Whether array a has the given shape (-1: any size there).
template <class A>
bool has_shape(const A& a, std::initializer_list<int64_t> shape) {
    if (a.ndim() != shape.size()) return false;
    size_t i = 0;
    for (int64_t s : shape) {
        if (s >= 0 && (int64_t)a.shape(i) != s) return false;
        ++i;
    }
    return true;
}

inline void require(bool ok, const char* what) {
    if (!ok) throw nb::value_error(what);
}

using Q1 = nb::ndarray<const double, nb::ndim<1>, nb::device::cpu>;

// exact_pairs' arrays, checked once: held (the arrays stay alive while this object does) and
// read at each call; the outputs are written in place.
struct ExactPairs {
    InI parent, perm, kind, qidx, g_int, o_int, self_pairs;
    In KR, Kp, g_float, vertices, o_float;
    Out R_WG, p_WG, out;
    OutI status, need, order;
    double tol;
    dmh::exact::Pairs P;

    ExactPairs(InI parent_, In KR_, In Kp_, InI perm_, InI kind_, InI qidx_, InI g_int_, In g_float_, In vertices_,
               InI o_int_, In o_float_, InI self_pairs_, double tol_, Out R_WG_, Out p_WG_, Out out_, OutI status_,
               OutI need_, OutI order_)
        : parent(parent_), perm(perm_), kind(kind_), qidx(qidx_), g_int(g_int_), o_int(o_int_),
          self_pairs(self_pairs_), KR(KR_), Kp(Kp_), g_float(g_float_), vertices(vertices_), o_float(o_float_),
          R_WG(R_WG_), p_WG(p_WG_), out(out_), status(status_), need(need_), order(order_), tol(tol_) {
        const int64_t F = (int64_t)parent.size(), G = (int64_t)g_int.size() / 5, K = (int64_t)o_int.size() / 2,
                      S = (int64_t)self_pairs.size() / 2, n = G * K + S;
        require(has_shape(parent, {F}) && has_shape(KR, {F, 3, 3}) && has_shape(Kp, {F, 3}) &&
                    has_shape(perm, {F, 3}) && has_shape(kind, {F}) && has_shape(qidx, {F}),
                "the chain: parent (F,), KR (F, 3, 3), Kp (F, 3), perm (F, 3), kind (F,), qidx (F,)");
        int64_t nq = 0;
        for (int64_t k = 0; k < F; ++k) {
            require(qidx.data()[k] >= 0 && parent.data()[k] < k, "qidx >= 0 and parents before their children");
            nq = std::max(nq, qidx.data()[k] + 1);
        }
        require(has_shape(g_int, {G, 5}) && has_shape(g_float, {G, 20}) && has_shape(vertices, {-1, 3}) &&
                    has_shape(o_int, {K, 2}) && has_shape(o_float, {K, 20}) && has_shape(self_pairs, {S, 2}),
                "g_int (G, 5), g_float (G, 20), vertices (V, 3), o_int (K, 2), o_float (K, 20), self_pairs (S, 2)");
        require(has_shape(R_WG, {G, 3, 3}) && has_shape(p_WG, {G, 3}) && has_shape(out, {n, 10}) &&
                    has_shape(status, {n}) && has_shape(need, {n}) && has_shape(order, {n}),
                "R_WG (G, 3, 3), p_WG (G, 3), out (n, 10), status, need, order (n,) with n = G K + S");
        const int64_t V = (int64_t)vertices.shape(0);
        for (int64_t g = 0; g < G; ++g) {
            const int64_t* r = g_int.data() + 5 * g;
            require(r[0] >= -1 && r[0] < F && (r[4] != dmh::gjk::HULL || (r[2] >= 0 && r[3] > 0 && r[2] + r[3] <= V)),
                    "a geometry's anchor frame or hull rows out of range");
        }
        for (int64_t k = 0; k < K; ++k)
            if (o_int.data()[2 * k + 1] == dmh::gjk::HULL) {
                const double* d = o_float.data() + 20 * k + 15;
                require(d[0] >= 0 && d[1] > 0 && d[0] + d[1] <= V, "an obstacle's hull rows out of range");
            }
        for (int64_t s = 0; s < 2 * S; ++s)
            require(self_pairs.data()[s] >= 0 && self_pairs.data()[s] < G, "a self pair's geometry out of range");
        P.chain = dmh::Chain{F, parent.data(), KR.data(), Kp.data(), perm.data(), kind.data(), qidx.data()};
        P.nq = nq, P.G = G, P.K = K, P.S = S;
        P.g_int = g_int.data(), P.o_int = o_int.data(), P.self_pairs = self_pairs.data();
        P.g_float = g_float.data(), P.o_float = o_float.data(), P.vertices = vertices.data();
        P.R_WG = R_WG.data(), P.p_WG = p_WG.data(), P.out = out.data();
        P.status = status.data(), P.need = need.data(), P.order = order.data();
    }

    nb::tuple operator()(Q1 q, double max_distance, bool min_only) const {
        require((int64_t)q.shape(0) == P.nq, "q must have shape (nq,)");
        int64_t n_need = 0, n_rows = 0;
        const double best =
            dmh::exact::exact_pairs(P, q.data(), (int64_t)q.stride(0), max_distance, min_only, tol, n_need, n_rows);
        return nb::make_tuple(best, n_need, n_rows);
    }
};

inline nb::tuple exact_pairs(Q1 q, InI parent, In KR, In Kp, InI perm, InI kind, InI qidx, InI g_int, In g_float,
                             In vertices, InI o_int, In o_float, InI self_pairs, double max_distance, bool min_only,
                             double tol, Out R_WG, Out p_WG, Out out, OutI status, OutI need, OutI order) {
    return ExactPairs(parent, KR, Kp, perm, kind, qidx, g_int, g_float, vertices, o_int, o_float, self_pairs, tol,
                      R_WG, p_WG, out, status, need, order)(q, max_distance, min_only);
}

inline void correct_clearances(Out values, nb::ndarray<const double, nb::ndim<3>, nb::device::cpu> points_W,
                               In radii, In c_G, In g_bound, InI g_start, InI g_kind, In half_length, In radius, In VH,
                               InI v_start, In NH, In OH, InI f_start, In EH, InI e_start, In excess, InI kinds,
                               In R_WO, In p_WO, In dims, In corners, InI n_corners, In normals, InI n_normals,
                               In edges, InI n_edges) {
    require(values.ndim() == 2, "values (n, K)");
    const int64_t n = (int64_t)values.shape(0), K = (int64_t)values.shape(1), G = (int64_t)g_bound.size(),
                  S = (int64_t)radii.size();
    require(has_shape(points_W, {n, 4 * G, 3}) && has_shape(c_G, {S, 3}) && has_shape(g_start, {G + 1}) &&
                has_shape(g_kind, {G}) && has_shape(half_length, {G}) && has_shape(radius, {G}) &&
                has_shape(v_start, {G + 1}) && has_shape(f_start, {G + 1}) && has_shape(e_start, {G + 1}) &&
                has_shape(excess, {G}) && has_shape(VH, {-1, 3}) && has_shape(NH, {-1, 3}) &&
                has_shape(OH, {(int64_t)NH.shape(0)}) && has_shape(EH, {-1, 3}),
            "the geometries' arrays (penetration.core_arrays) do not match values (n, K) and points_W (n, 4 G, 3)");
    require(has_shape(kinds, {-1}) && (int64_t)kinds.shape(0) >= K && has_shape(R_WO, {-1, 3, 3}) &&
                (int64_t)R_WO.shape(0) >= K && has_shape(p_WO, {-1, 3}) && (int64_t)p_WO.shape(0) >= K &&
                has_shape(dims, {-1, 3}) && (int64_t)dims.shape(0) >= K && has_shape(corners, {K, -1, 3}) &&
                has_shape(normals, {K, -1, 3}) && has_shape(edges, {K, -1, 3}) && has_shape(n_corners, {K}) &&
                has_shape(n_normals, {K}) && has_shape(n_edges, {K}),
            "the obstacles' arrays (scene obstacle_arrays, penetration.obstacle_polytopes) do not match values (n, K)");
    auto in_range = [](const InI& start, int64_t end) {
        for (size_t i = 0; i + 1 < start.size(); ++i)
            if (start.data()[i] < 0 || start.data()[i] > start.data()[i + 1]) return false;
        return start.data()[start.size() - 1] <= end;
    };
    require(in_range(g_start, S) && in_range(v_start, (int64_t)VH.shape(0)) &&
                in_range(f_start, (int64_t)NH.shape(0)) &&
                in_range(e_start, (int64_t)EH.shape(0)),
            "a geometry's rows out of range");
    for (int64_t k = 0; k < K; ++k)
        require(n_corners.data()[k] >= 0 && n_corners.data()[k] <= (int64_t)corners.shape(1) &&
                    n_normals.data()[k] >= 0 && n_normals.data()[k] <= (int64_t)normals.shape(1) &&
                    n_edges.data()[k] >= 0 && n_edges.data()[k] <= (int64_t)edges.shape(1),
                "an obstacle's polytope counts exceed its padded rows");
    dmh::penetration::Cores C;
    for (int i = 0; i < 3; ++i) C.ps[i] = (int64_t)points_W.stride(i);
    C.n = n, C.K = K, C.G = G, C.Vc = (int64_t)corners.shape(1), C.Fn = (int64_t)normals.shape(1),
    C.Ee = (int64_t)edges.shape(1);
    C.values = values.data(), C.points_W = points_W.data(), C.radii = radii.data(), C.c_G = c_G.data();
    C.g_bound = g_bound.data(), C.half_length = half_length.data(), C.radius = radius.data(), C.VH = VH.data();
    C.NH = NH.data(), C.OH = OH.data(), C.EH = EH.data(), C.excess = excess.data();
    C.g_start = g_start.data(), C.g_kind = g_kind.data(), C.v_start = v_start.data(), C.f_start = f_start.data();
    C.e_start = e_start.data(), C.kinds = kinds.data(), C.R_WO = R_WO.data(), C.p_WO = p_WO.data();
    C.dims = dims.data(), C.corners = corners.data(), C.normals = normals.data(), C.edges = edges.data();
    C.n_corners = n_corners.data(), C.n_normals = n_normals.data(), C.n_edges = n_edges.data();
    nb::gil_scoped_release unlocked;
    dmh::penetration::correct_clearances(C);
}

inline void bind_exact(nb::module_& m) {
    m.def("exact_pairs", &exact_pairs, "q"_a, "parent"_a, "KR"_a, "Kp"_a, "perm"_a, "kind"_a, "qidx"_a, "g_int"_a,
          "g_float"_a, "vertices"_a, "o_int"_a, "o_float"_a, "self_pairs"_a, "max_distance"_a, "min_only"_a, "tol"_a,
          nb::arg("R_WG").noconvert(), nb::arg("p_WG").noconvert(), nb::arg("out").noconvert(),
          nb::arg("status").noconvert(), nb::arg("need").noconvert(), nb::arg("order").noconvert(),
          "drake_mh.scene.kernels.exact.exact_pairs (the same arguments and answer): one configuration q (nq,)\n"
          "float64 (any stride); the outputs are written in place. Returns (best, n_need, n_rows), (nan, -1, 0)\n"
          "if q is not finite.");
    nb::class_<ExactPairs>(m, "ExactPairs",
        "exact_pairs' arrays (its arguments but q, max_distance and min_only; tol after self_pairs), checked\n"
        "once and held: a call (q, max_distance, min_only) is exact_pairs of them.")
        .def(nb::init<InI, In, In, InI, InI, InI, InI, In, In, InI, In, InI, double, Out, Out, Out, OutI, OutI, OutI>(),
             "parent"_a, "KR"_a, "Kp"_a, "perm"_a, "kind"_a, "qidx"_a, "g_int"_a, "g_float"_a, "vertices"_a,
             "o_int"_a, "o_float"_a, "self_pairs"_a, "tol"_a, nb::arg("R_WG").noconvert(), nb::arg("p_WG").noconvert(),
             nb::arg("out").noconvert(), nb::arg("status").noconvert(), nb::arg("need").noconvert(),
             nb::arg("order").noconvert())
        .def("__call__", &ExactPairs::operator(), "q"_a, "max_distance"_a, "min_only"_a,
             "(best, n_need, n_rows) of one configuration q (nq,) float64 (any stride); (nan, -1, 0) if not finite.");
    m.def("correct_clearances", &correct_clearances, nb::arg("values").noconvert(), "points_W"_a, "radii"_a, "c_G"_a,
          "g_bound"_a, "g_start"_a, "g_kind"_a, "half_length"_a, "radius"_a, "VH"_a, "v_start"_a, "NH"_a, "OH"_a,
          "f_start"_a, "EH"_a, "e_start"_a, "excess"_a, "kinds"_a, "R_WO"_a, "p_WO"_a, "dims"_a, "corners"_a,
          "n_corners"_a, "normals"_a, "n_normals"_a, "edges"_a, "n_edges"_a,
          "drake_mh.scene.penetration.correct_clearances (the same arguments): values (n, K) in place.");
}

}  // namespace dmh_bind
