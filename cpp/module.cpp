// drake_mh._native: the compiled core's entry points from Python (nanobind).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <cmath>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "borrow.hpp"
#include "collision.hpp"
#include "dynamics.hpp"
#include "exact_bind.hpp"
#include "paths_bind.hpp"
#include "segments.hpp"
#include "fk.hpp"
#include "cloud_build.hpp"
#include "lm.hpp"
#include "planner.hpp"
#include "ppoly.hpp"
#include "refine.hpp"
#include "topp.hpp"
#include "topp_rows.hpp"

namespace nb = nanobind;
using namespace nb::literals;

using Ints = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Floats = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Batch = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using One = nb::ndarray<const double, nb::ndim<1>, nb::device::cpu>;
using BoolOut = nb::ndarray<nb::numpy, bool, nb::ndim<1>>;

// A CollisionChecker or Clearances (a dmh::PackedModel) built in place on the buffers, borrowed.
template <class Model>
static void init_model(Model* self, Ints ints, Floats floats) {
    new (self) Model(dmh::borrow(ints, floats));
    if (!self->ok()) {
        self->~Model();
        throw nb::value_error("the packed buffers do not hold a collision model (drake_mh.scene.kernels.packing.pack)");
    }
}

using F64Out = nb::ndarray<nb::numpy, double>;
using Array = nb::ndarray<const double, nb::c_contig, nb::device::cpu>;  // any shape, checked by the caller's sizes
using IntArray = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Points = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;

template <class T>
static nb::ndarray<nb::numpy, T> owned(T* data, std::initializer_list<size_t> shape) {
    nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
    return nb::ndarray<nb::numpy, T>(data, shape, owner);
}

// q(t) = p(s(t)) from scipy PPoly arrays (timed_derivatives, certify_samples)
struct Timed {
    dmh::PPoly path, timing;
};

static Timed timed_of(const Array& path_c, const Floats& path_x, const std::optional<Array>& timing_c,
                      const std::optional<Floats>& timing_x) {
    if (path_c.ndim() != 3 || path_c.shape(1) < 1 || path_x.shape(0) != path_c.shape(1) + 1)
        throw nb::value_error("path: c (k + 1, m, nq) and x (m + 1,) of a scipy PPoly");
    if (timing_c.has_value() != timing_x.has_value() ||
        (timing_c && (timing_c->ndim() != 2 || timing_c->shape(1) < 1 || timing_x->shape(0) != timing_c->shape(1) + 1)))
        throw nb::value_error("timing: c (k + 1, m) and x (m + 1,) of a scalar scipy PPoly, or both None");
    Timed q{{path_c.data(), path_x.data(), (int64_t)path_c.shape(0) - 1, (int64_t)path_c.shape(1),
             (int64_t)path_c.shape(2)},
            {nullptr, nullptr, 0, 0, 1}};
    if (timing_c)
        q.timing = dmh::PPoly{timing_c->data(), timing_x->data(), (int64_t)timing_c->shape(0) - 1,
                              (int64_t)timing_c->shape(1), 1};
    return q;
}

// Checks the quantity kinds (0..4); where one is torque, reads the dynamics packed as
// drake_mh.trajectories.dynamics.BatchDynamics.packed says into dyn and returns true.
static bool kinds_need_dynamics(const int64_t* kinds, size_t n, int64_t nq, const std::optional<IntArray>& ints,
                                const std::optional<Floats>& floats, dmh::ChainDynamics& dyn) {
    bool torque = false;
    for (size_t i = 0; i < n; ++i) {
        if (kinds[i] < 0 || kinds[i] > dmh::TORQUE) throw nb::value_error("quantity kinds must be in 0..4");
        torque |= kinds[i] == dmh::TORQUE;
    }
    if (!torque) return false;
    if (!ints || !floats || ints->shape(0) % 3 != 0)
        throw nb::value_error("torque needs the packed dynamics (BatchDynamics.packed)");
    const int64_t F = (int64_t)ints->shape(0) / 3;
    if ((int64_t)floats->shape(0) != 25 * F + 3 + 2 * nq)
        throw nb::value_error("packed dynamics: floats must be 25 F + 3 + 2 nq");
    const int64_t* I = ints->data();
    const double* X = floats->data();
    for (int64_t k = 0; k < F; ++k)
        if (I[2 * F + k] < 0 || I[2 * F + k] >= nq || I[k] >= k)
            throw nb::value_error("packed dynamics: qidx in [0, nq) and frames in topological order");
    dyn.F = F, dyn.parent = I, dyn.kind = I + F, dyn.qidx = I + 2 * F;
    dyn.KR = X, dyn.Kp = X + 9 * F, dyn.mass = X + 12 * F, dyn.com = X + 13 * F, dyn.inertia = X + 16 * F;
    dyn.a_world = X + 25 * F, dyn.damping = X + 25 * F + 3, dyn.reflected = X + 25 * F + 3 + nq;
    return true;
}

static void init_kinematics(dmh::Kinematics* self, Ints ints, Floats floats) {
    const size_t F = ints.shape(0) / 6;
    if (ints.shape(0) != 6 * F || floats.shape(0) != 12 * F)
        throw nb::value_error("a chain packs 6 F ints (parent, perm (F, 3), kind, qidx) and 12 F floats (KR, Kp)");
    new (self) dmh::Kinematics(std::vector<int64_t>(ints.data(), ints.data() + ints.shape(0)),
                               std::vector<double>(floats.data(), floats.data() + floats.shape(0)));
}

static int free_one(dmh::CollisionChecker& self, One q, double clearance, double self_clearance) {
    if ((int64_t)q.shape(0) != self.nq()) return -3;
    std::lock_guard<std::mutex> one_call(self.busy);  // (the GIL is held: a short call)
    return self.free_one(q.data(), (int64_t)q.stride(0), clearance, self_clearance);
}

static bool all_finite(const double* x, size_t n) {
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(x[i])) return false;
    return true;
}

// v_WO (K, 3) of the checker's K obstacles, finite, or a ValueError
// TOPP-RA's gridpoints (N + 1,): finite and strictly increasing, else a ValueError naming the call.
static void check_gridpoints(const Floats& gp, const char* call) {
    const double* x = gp.data();
    for (size_t i = 0; i + 1 < gp.shape(0); ++i)
        if (!(x[i + 1] > x[i]) || !std::isfinite(x[i + 1]) || !std::isfinite(x[i]))
            throw nb::value_error((std::string(call) + ": the gridpoints must be finite and strictly increasing").c_str());
}

static void check_v_WO(const dmh::Clearances& self, Batch v_WO) {
    if ((int64_t)v_WO.shape(0) != self.packed().K || v_WO.shape(1) != 3 || !all_finite(v_WO.data(), v_WO.size()))
        throw nb::value_error("v_WO must be finite (K, 3) float64, K the packed obstacles");
}

static const char* FREE_ONE =
    "One configuration q (nq,) float64 (any stride): 1 free, 0 not, -1 not finite, -2 a clearance\n"
    "not in [0, inf), -3 a wrong size.";

NB_MODULE(_native, m) {
    m.doc() = "drake_mh's compiled core (C++): the sphere-model collision check and clearance values, certified "
              "segments, forward kinematics, point clouds' tables, rrt_connect's planner and certified motion check, "
              "the Levenberg-Marquardt IK, inverse dynamics and trajectory bounds.";
    m.attr("simd_width") = dmh::W;
    m.attr("lanes") = dmh::CollisionChecker::LANES;
    dmh_bind::bind_exact(m);
    dmh_bind::bind_paths(m);

    nb::class_<dmh::Kinematics>(m, "Kinematics",
        "Batched forward kinematics of a compiled chain (drake_mh.kinematics.BatchKinematics): ints =\n"
        "[parent, perm (F, 3), kind, qidx], floats = [KR (F, 3, 3), Kp (F, 3)].")
        .def("__init__", &init_kinematics, "ints"_a, "floats"_a)
        .def_prop_ro("nq", &dmh::Kinematics::nq)
        .def("moving_frames", [](dmh::Kinematics& self, Batch Q) {
            const size_t N = Q.shape(0), F = (size_t)self.F();
            if ((int64_t)Q.shape(1) != self.nq()) throw nb::value_error("Q must have shape (N, nq)");
            double* R = new double[N * F * 9 + 1];
            double* p = new double[N * F * 3 + 1];
            {
                nb::gil_scoped_release unlocked;
                std::lock_guard<std::mutex> one_call(self.busy);
                self.moving_frames(Q.data(), (int64_t)N, R, p);
            }
            return nb::make_tuple(owned(R, {N, F, 3, 3}), owned(p, {N, F, 3}));
        }, "Q"_a, "R_WF (N, F, 3, 3) and p_WF (N, F, 3) of finite Q (N, nq).")
        .def("fk_jacobian", [](dmh::Kinematics& self, Batch Q, int64_t anchor, Floats ER, Floats Ep,
                               nb::ndarray<const bool, nb::ndim<1>, nb::c_contig, nb::device::cpu> on_path, bool want_jac) {
            const size_t N = Q.shape(0), nq = (size_t)self.nq();
            if (Q.shape(1) != nq || ER.shape(0) != 9 || Ep.shape(0) != 3 || on_path.shape(0) != (size_t)self.F() ||
                anchor < -1 || anchor >= self.F())
                throw nb::value_error("Q (N, nq), ER (9,), Ep (3,), on_path (F,), -1 <= anchor < F");
            double* T = new double[N * 16 + 1];
            double* J = want_jac ? new double[N * 6 * nq + 1] : nullptr;
            {
                nb::gil_scoped_release unlocked;
                std::lock_guard<std::mutex> one_call(self.busy);
                self.fk_jacobian(Q.data(), (int64_t)N, anchor, ER.data(), Ep.data(), on_path.data(), T, J);
            }
            if (!want_jac) return nb::make_tuple(owned(T, {N, 4, 4}), nb::none());
            return nb::make_tuple(owned(T, {N, 4, 4}), owned(J, {N, 6, nq}));
        }, "Q"_a, "anchor"_a, "ER"_a, "Ep"_a, "on_path"_a, "want_jac"_a,
        "X_WF (N, 4, 4) and (want_jac) J (N, 6, nq) of the frame at (ER, Ep) in moving frame anchor.")
        .def("fk_jacobian_one", [](dmh::Kinematics& self, One q, int64_t anchor, Floats ER, Floats Ep,
                                   nb::ndarray<const bool, nb::ndim<1>, nb::c_contig, nb::device::cpu> on_path,
                                   nb::ndarray<double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu> T,
                                   nb::ndarray<double, nb::ndim<2>, nb::c_contig, nb::device::cpu> J, bool want_jac) {
            const size_t nq = (size_t)self.nq();
            if (q.shape(0) != nq || ER.shape(0) != 9 || Ep.shape(0) != 3 || on_path.shape(0) != (size_t)self.F() ||
                anchor < -1 || anchor >= self.F() || (want_jac && (J.shape(0) != 6 || J.shape(1) != nq)))
                throw nb::value_error("q (nq,), ER (9,), Ep (3,), on_path (F,), J (6, nq), -1 <= anchor < F");
            std::lock_guard<std::mutex> one_call(self.busy);  // (the GIL is held: a short call)
            return self.fk_jacobian_one(q.data(), (int64_t)q.stride(0), anchor, ER.data(), Ep.data(), on_path.data(),
                                        T.data(), want_jac ? J.data() : nullptr);
        }, "q"_a, "anchor"_a, "ER"_a, "Ep"_a, "on_path"_a, "T"_a, "J"_a, "want_jac"_a,
        "Writes X_WF into T (4, 4) and, with want_jac, the Jacobian into J (6, nq), of one configuration q (nq,)\n"
        "float64 (any stride); False (nothing written) if q is not finite.");

    nb::class_<dmh::CollisionChecker>(m, "CollisionChecker",
        "The boolean sphere-model check of a scene's packed arrays (drake_mh.scene.kernels.packing.pack):\n"
        "the answers of drake_mh.scene.kernels.collision.collision_free. Holds copies of the buffers and\n"
        "its own workspace: calls on one checker run one at a time; a batched call releases the GIL.")
        .def("__init__", &init_model<dmh::CollisionChecker>, "ints"_a, "floats"_a)
        .def_prop_ro("nq", &dmh::CollisionChecker::nq)
        .def("free", [](dmh::CollisionChecker& self, Batch Q, double clearance, double self_clearance) -> nb::object {
            const int64_t N = (int64_t)Q.shape(0), nq = (int64_t)Q.shape(1);
            if (nq != self.nq()) throw nb::value_error("Q must have shape (N, nq)");
            bool* out = new bool[N > 0 ? N : 1];
            nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<bool*>(p); });
            bool finite;
            {
                nb::gil_scoped_release unlocked;
                std::lock_guard<std::mutex> one_call(self.busy);
                finite = self.free_batch(Q.data(), N, nq, clearance, self_clearance, out);
            }
            if (!finite) return nb::none();
            return nb::cast(BoolOut(out, {(size_t)N}, owner));
        }, "Q"_a, "clearance"_a, "self_clearance"_a,
        "(N,) bool for Q (N, nq) C-contiguous float64, clearances > 0 [m]; None if Q is not finite.")
        .def("free_one", &free_one, "q"_a, "clearance"_a, "self_clearance"_a, FREE_ONE);

    nb::class_<dmh::Clearances>(m, "Clearances",
        "Clearance values of a scene's packed arrays (drake_mh.scene.kernels.packing.pack): the values of\n"
        "drake_mh.scene.kernels.collision.link_clearances and the verdicts of\n"
        "drake_mh.scene.kernels.segments.certify_segments. Holds copies of the buffers and its own\n"
        "workspace: calls on one object run one at a time, with the GIL released.")
        .def("__init__", &init_model<dmh::Clearances>, "ints"_a, "floats"_a)
        .def_prop_ro("nq", &dmh::Clearances::nq)
        .def("values", [](dmh::Clearances& self, Batch Q, Floats tau, double fine_below, Floats pair_fine_below,
                          int mode, Batch v_WO) -> nb::object {
            const int64_t N = (int64_t)Q.shape(0);
            const bool still = tau.shape(0) == 0;  // no tau: the obstacles where they are
            if ((int64_t)Q.shape(1) != self.nq() || (!still && (int64_t)tau.shape(0) != N) ||
                (int64_t)pair_fine_below.shape(0) != self.packed().P || mode < dmh::PER_LINK || mode > dmh::OVERALL)
                throw nb::value_error("Q (N, nq), tau (N,), pair_fine_below (P,), mode 0, 1 or 2");
            check_v_WO(self, v_WO);
            if (!all_finite(tau.data(), tau.shape(0))) throw nb::value_error("tau must be finite");
            if (!all_finite(Q.data(), Q.size())) return nb::none();
            const size_t width = (size_t)self.width(mode);
            double* out = new double[(size_t)N * width + 1];
            {
                nb::gil_scoped_release unlocked;
                std::lock_guard<std::mutex> one_call(self.busy);
                std::vector<double> zeros(still ? (size_t)N : 0, 0.0);
                self.evaluate(Q.data(), N, still ? zeros.data() : tau.data(), fine_below, pair_fine_below.data(), mode,
                              v_WO.data(), out);
            }
            return nb::cast(owned(out, {(size_t)N, width}));
        }, "Q"_a, "tau"_a, "fine_below"_a, "pair_fine_below"_a, "mode"_a, "v_WO"_a,
        "(N, width) float64 for Q (N, nq) C-contiguous (None if Q is not finite), obstacles at p_WO + tau v_WO\n"
        "(tau (N,), or empty: 0):\n"
        "mode 0 per link and pair (width G + P), 1 per obstacle (K), 2 over all obstacles (1).")
        .def("certify_segments", [](dmh::Clearances& self, Batch QA, Batch QB, Batch reach, Batch v_WO, double speed,
                                    double clearance, double self_clearance, double tolerance, double min_piece,
                                    int64_t max_evals) {
            const size_t M = QA.shape(0), nq = (size_t)self.nq(), C = (size_t)(self.packed().G + self.packed().P);
            if (QA.shape(1) != nq || QB.shape(0) != M || QB.shape(1) != nq || reach.shape(0) != C || reach.shape(1) != nq)
                throw nb::value_error("QA, QB (M, nq), reach (G + P, nq)");
            check_v_WO(self, v_WO);
            if (!all_finite(QA.data(), QA.size()) || !all_finite(QB.data(), QB.size()) ||
                !all_finite(reach.data(), reach.size()) || !std::isfinite(speed) || !std::isfinite(clearance) ||
                !std::isfinite(self_clearance) || !(tolerance > 0.0) || !(min_piece > 0.0) || max_evals < 2)
                throw nb::value_error("finite QA, QB, reach, speed and clearances; tolerance > 0, min_piece > 0, max_evals >= 2");
            int64_t* status = new int64_t[M + 1];
            int64_t* evals = new int64_t[M + 1];
            double* t_stop = new double[M + 1];
            double* lower = new double[M + 1];
            double* lower_self = new double[M + 1];
            {
                nb::gil_scoped_release unlocked;
                std::lock_guard<std::mutex> one_call(self.busy);
                dmh::certify_segments(self, QA.data(), QB.data(), (int64_t)M, reach.data(), v_WO.data(), speed,
                                      clearance, self_clearance, tolerance, min_piece, max_evals, status, t_stop,
                                      lower, lower_self, evals);
            }
            return nb::make_tuple(owned(status, {M}), owned(t_stop, {M}), owned(lower, {M}), owned(lower_self, {M}),
                                  owned(evals, {M}));
        }, "QA"_a, "QB"_a, "reach"_a, "v_WO"_a, "speed"_a, "clearance"_a, "self_clearance"_a, "tolerance"_a,
        "min_piece"_a, "max_evals"_a,
        "(status, t_stop, lower, lower_self, evals) (M,) each of the segments QA[i] -> QB[i] (M, nq):\n"
        "drake_mh.scene.kernels.segments.certify_segments, v_WO (K, 3) the obstacles' displacement per segment.");

    bind_planner(m);

    m.def("cloud_table", [](Points P, double radius, double h_min, double max_cells) {
        const size_t N = P.shape(0);
        const double* p = P.data();
        if (N == 0 || N >= (size_t(1) << 32)) throw nb::value_error("cloud_table: from 1 to 2^32 - 1 points");
        for (size_t j = 0; j < 3 * N; ++j)
            if (!std::isfinite(p[j])) throw nb::value_error("cloud_table: the points must be finite");
        if (!(radius >= 0.0 && h_min > 0.0 && max_cells >= 1.0 && std::isfinite(radius) && std::isfinite(h_min) &&
              std::isfinite(max_cells)))
            throw nb::value_error("cloud_table: radius >= 0, h_min > 0 and max_cells >= 1, finite");
        double* low = new double[3];
        double* high = new double[3];
        dmh::CloudTable table;
        {
            nb::gil_scoped_release unlocked;
            table = dmh::cloud_table(p, (int64_t)N, radius, h_min, max_cells, low, high);
        }
        return nb::make_tuple(owned(table.data.release(), {(size_t)table.rows, 3}), owned(low, {3}), owned(high, {3}));
    }, "P"_a, "radius"_a, "h_min"_a, "max_cells"_a,
    "(table (rows, 3), low (3,), high (3,)) of finite points P (N, 3) C-contiguous float64: a point\n"
    "cloud's shape-table entry, drake_mh.scene.kernels.cloud.cloud_table (the same table), and the\n"
    "points' bounding box.");

    // lm.py lm_run / lm_step: the state arrays are BatchLM's, written in place
    using RW = nb::ndarray<double, nb::c_contig, nb::device::cpu>;
    using RWi = nb::ndarray<int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
    using RWb = nb::ndarray<bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
    using Bools = nb::ndarray<const bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
    struct LMArgs {
        dmh::LMState S;
        dmh::LMProblem P;
        std::vector<double> r;
    };
    auto lm_args = [](RW Qt, RW Qa, RW Ea, RW Ja, RW fa, RW lam, RWi stall, RWi iters, RWb fresh, RWi status, RW Qn,
                      nb::tuple problem, nb::tuple settings, Bools revolute) {
        const size_t K = Qt.ndim() == 2 ? Qt.shape(0) : 0, nq = Qt.ndim() == 2 ? Qt.shape(1) : 0;
        auto shaped = [](auto& a, std::initializer_list<size_t> shape) {
            if (a.ndim() != shape.size()) return false;
            size_t i = 0;
            for (size_t n : shape)
                if (a.shape(i++) != n) return false;
            return true;
        };
        if (!shaped(Qt, {K, nq}) || !shaped(Qa, {K, nq}) || !shaped(Ea, {K, 6}) || !shaped(Ja, {K, 6, nq}) ||
            !shaped(fa, {K}) || !shaped(lam, {K}) || stall.shape(0) != K || iters.shape(0) != K ||
            fresh.shape(0) != K || status.shape(0) != K || !shaped(Qn, {K, nq}) || revolute.shape(0) != nq ||
            nb::len(problem) != 17 || nb::len(settings) != 9)
            throw nb::value_error("lm: the state of K candidates of nq joints (drake_mh.ik.lm.BatchLM)");
        LMArgs a;
        a.r.assign(nq + 1, 0.0);
        a.S = dmh::LMState{(int64_t)K, (int64_t)nq, Qt.data(), Qa.data(), Ea.data(), Ja.data(), fa.data(),
                           lam.data(), stall.data(), iters.data(), status.data(), fresh.data(), Qn.data(), a.r.data()};
        // problem = BatchLM._const: p_t, R_t, has_rot, w_o, lower, upper, (settings 7), ref_gain, q_ref, tol_p2, tol_o2
        auto vec = [&](nb::handle h, size_t n) {
            auto v = nb::cast<Floats>(h);
            if (v.shape(0) != n) throw nb::value_error("lm: a problem vector of the wrong size");
            return v.data();
        };
        dmh::LMProblem& P = a.P;
        P.p_t = vec(problem[0], 3);
        P.R_t = nb::cast<Batch>(problem[1]).data();
        if (nb::cast<Batch>(problem[1]).shape(0) != 3 || nb::cast<Batch>(problem[1]).shape(1) != 3)
            throw nb::value_error("lm: R_t must be (3, 3)");
        P.has_rot = nb::cast<bool>(problem[2]);
        P.w_o = nb::cast<double>(problem[3]);
        P.lower = vec(problem[4], nq), P.upper = vec(problem[5], nq);
        P.adaptive = nb::cast<bool>(settings[0]);
        P.lam_down = nb::cast<double>(settings[1]), P.lam_up = nb::cast<double>(settings[2]);
        P.lam_min = nb::cast<double>(settings[3]), P.lam_max = nb::cast<double>(settings[4]);
        P.max_iter = nb::cast<int64_t>(settings[5]), P.stall_iters = nb::cast<int64_t>(settings[6]);
        P.project = nb::cast<bool>(settings[7]), P.error_damping = nb::cast<bool>(settings[8]);
        P.ref_gain = nb::cast<double>(problem[13]);
        P.q_ref = vec(problem[14], nq);
        P.tol_p2 = nb::cast<double>(problem[15]), P.tol_o2 = nb::cast<double>(problem[16]);
        P.revolute = revolute.data();
        return a;
    };
    m.def("lm_step", [lm_args](Array T, Array J, RW Qt, RW Qa, RW Ea, RW Ja, RW fa, RW lam, RWi stall, RWi iters,
                               RWb fresh, RWi status, RW Qn, nb::tuple problem) {
        const size_t K = Qt.ndim() == 2 ? Qt.shape(0) : 0, nq = Qt.ndim() == 2 ? Qt.shape(1) : 0;
        nb::tuple settings = nb::make_tuple(problem[6], problem[7], problem[8], problem[9], problem[10], problem[11],
                                            problem[12], true, false);
        bool* no_turns = new bool[nq + 1]();  // (project: the limits are never wrapped into)
        nb::capsule keep(no_turns, [](void* p) noexcept { delete[] static_cast<bool*>(p); });
        LMArgs a = lm_args(Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status, Qn, problem, settings,
                           Bools(no_turns, {nq}, keep));
        if (T.size() != 16 * K || J.size() != 6 * nq * K) throw nb::value_error("lm_step: T (K, 4, 4), J (K, 6, nq)");
        return dmh::lm_step(T.data(), J.data(), a.S, a.P);
    }, "T"_a, "J"_a, "Qt"_a, "Qa"_a, "Ea"_a, "Ja"_a, "fa"_a, "lam"_a, "stall"_a, "iters"_a, "fresh"_a, "status"_a,
    "Qn"_a, "problem"_a,
    "drake_mh.ik.lm.lm_step: one iteration of every candidate at its poses T and Jacobians J; the state\n"
    "arrays written in place; problem = BatchLM's constants. The converged row with the smallest error, or -1.");
    m.def("lm_run", [lm_args](dmh::Kinematics& kin, int64_t anchor, Floats ER, Floats Ep, Bools on_path, Batch starts,
                              int64_t n_starts, uint64_t gen_seed, int64_t cursor, int64_t max_evals, RW Qt, RW Qa,
                              RW Ea, RW Ja, RW fa, RW lam, RWi stall, RWi iters, RWb fresh, RWi status, RW best_q,
                              RW best_f, nb::tuple problem, double lam0, nb::tuple settings, Bools revolute, RW Qn,
                              RW T, RW J) {
        LMArgs a = lm_args(Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status, Qn, problem, settings, revolute);
        const int64_t K = a.S.K, nq = a.S.nq;
        if (nq != kin.nq() || ER.shape(0) != 9 || Ep.shape(0) != 3 || on_path.shape(0) != (size_t)kin.F() ||
            anchor < -1 || anchor >= kin.F() || (starts.shape(0) > 0 && (int64_t)starts.shape(1) != nq) ||
            best_q.size() != (size_t)nq || best_f.size() != 1 || T.size() != (size_t)(16 * K) ||
            J.size() != (size_t)(6 * nq * K) || cursor < 0)
            throw nb::value_error("lm_run: the chain's frame, starts (M, nq), best_q (nq,), best_f (1,), T, J");
        int64_t evals = 0, row;
        {
            nb::gil_scoped_release unlocked;
            std::lock_guard<std::mutex> one_call(kin.busy);
            row = dmh::lm_run(kin, anchor, ER.data(), Ep.data(), on_path.data(), starts.data(),
                              (int64_t)starts.shape(0), n_starts, gen_seed, cursor, max_evals, evals, a.S, a.P, lam0,
                              best_q.data(), best_f.data(), T.data(), J.data());
        }
        return nb::make_tuple(row, evals, cursor);
    }, "kinematics"_a, "anchor"_a, "ER"_a, "Ep"_a, "on_path"_a, "starts"_a, "n_starts"_a, "gen_seed"_a, "cursor"_a,
    "max_evals"_a, "Qt"_a, "Qa"_a, "Ea"_a, "Ja"_a, "fa"_a, "lam"_a, "stall"_a, "iters"_a, "fresh"_a, "status"_a,
    "best_q"_a, "best_f"_a, "problem"_a, "lam0"_a, "settings"_a, "revolute"_a, "Qn"_a, "T"_a, "J"_a,
    "drake_mh.ik.lm.lm_run on the compiled chain kin (frame at (ER, Ep) in moving frame anchor): iterations with\n"
    "restarts until a candidate converges; the state written in place. (row, evals, cursor).");

    m.def("rnea", [](IntArray parent, Array KR, Array Kp, IntArray kind, IntArray qidx, Array mass, Array com,
                     Array inertia, Array a_world, Batch Q, Batch V, Batch A) {
        const size_t F = parent.shape(0), N = Q.shape(0), nq = Q.shape(1);
        if (KR.size() != 9 * F || Kp.size() != 3 * F || kind.shape(0) != F || qidx.shape(0) != F ||
            mass.size() != F || com.size() != 3 * F || inertia.size() != 9 * F || a_world.size() != 3 ||
            V.shape(0) != N || V.shape(1) != nq || A.shape(0) != N || A.shape(1) != nq)
            throw nb::value_error("rnea: a chain of F frames and Q, V, A of one shape (N, nq)");
        for (size_t k = 0; k < F; ++k)
            if (qidx.data()[k] < 0 || qidx.data()[k] >= (int64_t)nq || parent.data()[k] >= (int64_t)k)
                throw nb::value_error("rnea: qidx must be in [0, nq) and frames in topological order");
        double* tau = new double[N * nq + 1];
        {
            nb::gil_scoped_release unlocked;
            dmh::rnea((int64_t)F, parent.data(), KR.data(), Kp.data(), kind.data(), qidx.data(), mass.data(),
                      com.data(), inertia.data(), a_world.data(), Q.data(), V.data(), A.data(), (int64_t)N,
                      (int64_t)nq, tau);
        }
        return owned(tau, {N, nq});
    }, "parent"_a, "KR"_a, "Kp"_a, "kind"_a, "qidx"_a, "mass"_a, "com"_a, "inertia"_a, "a_world"_a, "Q"_a, "V"_a, "A"_a,
    "Joint torques tau (N, nq) [N m] of Q, V, A (N, nq) C-contiguous float64: the recursive Newton-Euler\n"
    "algorithm of drake_mh.trajectories.dynamics.BatchDynamics (without its damping and rotor terms).");

    m.def("timed_derivatives", [](Array path_c, Floats path_x, std::optional<Array> timing_c,
                                  std::optional<Floats> timing_x, Floats T, int order) {
        if (order < 0 || order > 3) throw nb::value_error("timed_derivatives: order 0..3");
        const Timed q = timed_of(path_c, path_x, timing_c, timing_x);
        const size_t M = T.shape(0), nq = (size_t)q.path.d, rows = (size_t)order + 1;
        double* out = new double[rows * M * nq + 1];
        {
            nb::gil_scoped_release unlocked;
            dmh::timed_derivatives(q.path, q.timing, T.data(), (int64_t)M, order, out);
        }
        return owned(out, {rows, M, nq});
    }, "path_c"_a, "path_x"_a, "timing_c"_a.none(), "timing_x"_a.none(), "T"_a, "order"_a,
    "[q, q', ..., q^(order)] (order + 1, M, nq) of q(t) = p(s(t)) at times T (M,): p a scipy PPoly's\n"
    "c (k + 1, m, nq) and x (m + 1,), s the timing's c (k + 1, m) and x (None: q = p(t)); scipy's piece\n"
    "choice (right-continuous, extrapolating) and drake_mh.trajectories.Trajectory.derivatives' chain rule.");

    m.def("certify_samples", [](Array path_c, Floats path_x, std::optional<Array> timing_c,
                                std::optional<Floats> timing_x, Floats breaks, Floats tau, IntArray kinds,
                                Batch centre, Batch half, double threshold, int64_t per_joint, int64_t iterations,
                                std::optional<IntArray> dyn_ints, std::optional<Floats> dyn_floats,
                                std::optional<IntArray> bound_n1, std::optional<IntArray> bound_picks,
                                std::optional<Floats> bound_mats, double slack, int64_t max_levels) {
        const Timed q = timed_of(path_c, path_x, timing_c, timing_x);
        const size_t nQ = kinds.shape(0), nq = (size_t)q.path.d, P = breaks.shape(0) - 1, K = tau.shape(0);
        if (breaks.shape(0) < 2 || K < 2 || centre.shape(0) != nQ || centre.shape(1) != nq ||
            half.shape(0) != nQ || half.shape(1) != nq || per_joint < 0 || iterations < 0)
            throw nb::value_error("certify_samples: breaks (P + 1 >= 2,), tau (K >= 2,), centre and half (nQ, nq)");
        dmh::ChainDynamics dyn;
        const bool torque = kinds_need_dynamics(kinds.data(), nQ, q.path.d, dyn_ints, dyn_floats, dyn);
        int order = 0;
        for (size_t i = 0; i < nQ; ++i) order = std::max(order, kinds.data()[i] == dmh::TORQUE ? 2 : (int)kinds.data()[i]);
        const size_t M = P * K;
        if (bound_n1) {  // the Bernstein bounds' nodes: n1 per quantity, picks and matrices of those with n1 > 0
            size_t picks = 0, mats = 0;
            bool ok = bound_n1->shape(0) == nQ && bound_picks && bound_mats && max_levels >= 0;
            for (size_t i = 0; ok && i < nQ; ++i) {
                const int64_t n1 = bound_n1->data()[i];
                ok = n1 >= 0 && n1 <= (int64_t)K && (n1 == 0 || kinds.data()[i] < dmh::TORQUE);
                picks += (size_t)std::max<int64_t>(n1, 0), mats += 3 * (size_t)(n1 * n1);
            }
            ok = ok && bound_picks->shape(0) == picks && bound_mats->shape(0) == mats;
            for (size_t i = 0; ok && i < picks; ++i) ok = bound_picks->data()[i] >= 0 && bound_picks->data()[i] < (int64_t)K;
            if (!ok)
                throw nb::value_error("certify_samples: bound_n1 (nQ,) in [0, K] (0 for torque), bound_picks (sum n1,) "
                                      "in [0, K), bound_mats (sum 3 n1^2,)");
        }
        double* D = new double[((size_t)order + 1) * M * nq + 1];
        double* worst = new double[nQ * nq + 1];
        double* when = new double[nQ * nq + 1];
        {
            nb::gil_scoped_release unlocked;
            dmh::certify_samples(q.path, q.timing, torque ? &dyn : nullptr, breaks.data(), (int64_t)P, tau.data(),
                                 (int64_t)K, kinds.data(), centre.data(), half.data(), (int64_t)nQ, order, threshold,
                                 per_joint, iterations, D, worst, when);
            if (bound_n1)
                dmh::sample_bounds(D, (int64_t)P, (int64_t)K, (int64_t)nq, kinds.data(), (int64_t)nQ, bound_n1->data(),
                                   bound_picks->data(), bound_mats->data(), centre.data(), half.data(), slack, max_levels,
                                   worst);
        }
        return nb::make_tuple(owned(worst, {nQ, nq}), owned(when, {nQ, nq}), owned(D, {(size_t)order + 1, M, nq}));
    }, "path_c"_a, "path_x"_a, "timing_c"_a.none(), "timing_x"_a.none(), "breaks"_a, "tau"_a, "kinds"_a, "centre"_a,
    "half"_a, "threshold"_a, "per_joint"_a, "iterations"_a, "dyn_ints"_a.none() = nb::none(),
    "dyn_floats"_a.none() = nb::none(), "bound_n1"_a.none() = nb::none(), "bound_picks"_a.none() = nb::none(),
    "bound_mats"_a.none() = nb::none(), "slack"_a = 1e-8, "max_levels"_a = 30,
    "The sampled and refined ratios of drake_mh.trajectories.certify.certify for nQ quantities (kinds 0..3:\n"
    "the derivative of that order, 4: torque; |x - centre| / half per joint) at fractions tau of every piece between breaks:\n"
    "(worst (nQ, nq), when (nQ, nq) [s], D (order + 1, P K, nq) the derivatives at the samples). With bound_n1:\n"
    "worst also at least kinematic_bound's Bernstein bound from the samples (sample_bounds in refine.hpp).");

    m.def("bernstein_bound", [](Array B, Array V, Array centre, Array half, Array best, double slack,
                                int64_t max_levels, Array left, Array right) {
        if (B.ndim() != 3 || V.ndim() != 3 || left.ndim() != 2 || right.ndim() != 2)
            throw nb::value_error("bernstein_bound: B (P, n1, nq), V (Pv, m, nq), left and right (n1, n1)");
        const size_t P = B.shape(0), n1 = B.shape(1), nq = B.shape(2);
        if (V.shape(2) != nq || centre.size() != nq || half.size() != nq || best.size() != nq ||
            left.shape(0) != n1 || left.shape(1) != n1 || right.shape(0) != n1 || right.shape(1) != n1 ||
            max_levels < 0)
            throw nb::value_error("bernstein_bound: centre, half, best (nq,); left, right (n1, n1); max_levels >= 0");
        double* out = new double[nq + 1];
        {
            nb::gil_scoped_release unlocked;
            dmh::bernstein_bound(B.data(), (int64_t)P, (int64_t)n1, (int64_t)nq, V.data(), (int64_t)V.shape(0),
                                 (int64_t)V.shape(1), centre.data(), half.data(), best.data(), slack, max_levels,
                                 left.data(), right.data(), out);
        }
        return owned(out, {nq});
    }, "B"_a, "V"_a, "centre"_a, "half"_a, "best"_a, "slack"_a, "max_levels"_a, "left"_a, "right"_a,
    "Per joint, the bound (nq,) of drake_mh.trajectories.bound.kinematic_bound's halving loop on the Bernstein\n"
    "coefficients B (P, n1, nq) (values seen V (Pv, m, nq); de Casteljau's halves left, right (n1, n1)).");

    m.def("topp_ra", [](Floats gp, Batch A, Batch B, Batch C, Floats x_lo, Floats x_hi) {
        const size_t N1 = gp.shape(0), R = A.shape(1);
        if (N1 < 2 || A.shape(0) != N1 || B.shape(0) != N1 || C.shape(0) != N1 || B.shape(1) != R ||
            C.shape(1) != R || x_lo.shape(0) != N1 || x_hi.shape(0) != N1)
            throw nb::value_error("topp_ra: gridpoints (N+1,) with N >= 1; rows A, B, C (N+1, R); x_lo, x_hi (N+1,)");
        check_gridpoints(gp, "topp_ra");
        if (!all_finite(A.data(), A.size()) || !all_finite(B.data(), B.size()) || !all_finite(C.data(), C.size()))
            throw nb::value_error("topp_ra: the rows A, B, C must be finite");
        for (size_t i = 0; i < N1; ++i)
            if (std::isnan(x_lo.data()[i]) || std::isnan(x_hi.data()[i]))
                throw nb::value_error("topp_ra: x_lo, x_hi must not be NaN (-inf, inf: no bound)");
        double* K = new double[2 * N1];
        double* xs = new double[N1];
        double* us = new double[N1];
        int64_t stage;
        {
            nb::gil_scoped_release unlocked;
            for (size_t i = 0; i < N1; ++i) xs[i] = NAN, us[i] = NAN, K[2 * i] = NAN, K[2 * i + 1] = NAN;
            stage = dmh::topp_ra(gp.data(), (int64_t)N1, A.data(), B.data(), C.data(), (int64_t)R, x_lo.data(),
                                 x_hi.data(), K, xs, us);
        }
        return nb::make_tuple(stage, owned(xs, {N1}), owned(us, {N1 - 1}), owned(K, {N1, 2}));
    }, "gridpoints"_a, "A"_a, "B"_a, "C"_a, "x_lo"_a, "x_hi"_a,
    "TOPP-RA from rest to rest (the toppra package's TOPPRA with its seidel solver): stage i's rows\n"
    "A[i] u + B[i] x + C[i] <= 0 (N+1, R) in u = s'' on [s_i, s_{i+1}] and x = s'^2 at s_i, bounds\n"
    "x_lo[i] <= x_i <= x_hi[i]. (stage, xs (N+1,), us (N,), K (N+1, 2)): stage -1 solved, else the\n"
    "stage where it failed (xs then NaN from there on).");

    m.def("spline_gridpoints", [](Array c, Floats x, double max_err, int64_t max_iteration, double max_seg,
                                  int64_t min_nb) {
        const dmh::PPoly sp = timed_of(c, x, std::nullopt, std::nullopt).path;
        std::vector<double> gp;
        bool settled;
        {
            nb::gil_scoped_release unlocked;
            settled = dmh::spline_gridpoints(sp, max_err, max_iteration, max_seg, min_nb, gp);
        }
        if (!settled) throw nb::value_error("Unable to find a good gridpoint for this path.");
        double* out = new double[gp.size()];
        std::copy(gp.begin(), gp.end(), out);
        return owned(out, {gp.size()});
    }, "c"_a, "x"_a, "max_err"_a, "max_iteration"_a, "max_seg"_a, "min_nb"_a,
    "toppra's gridpoints on a joint spline (scipy PPoly c (k + 1, m, nq), x (m + 1,) from 0), its knots added:\n"
    "drake_mh.trajectories.toppra_time._gridpoints with gridpoints=None.");

    m.def("spline_topp_ra", [](Array c, Floats x, Floats gp, Floats vmax, Floats amax, Floats tmax, Floats phi,
                               bool velocity_bound, std::optional<IntArray> dyn_ints, std::optional<Floats> dyn_floats) {
        const dmh::PPoly sp = timed_of(c, x, std::nullopt, std::nullopt).path;
        const size_t N1 = gp.shape(0), nq = (size_t)sp.d;
        if (N1 < 2 || vmax.shape(0) != nq || amax.shape(0) != nq || tmax.shape(0) != nq || phi.shape(0) < 1)
            throw nb::value_error("spline_topp_ra: gridpoints (N+1 >= 2,), vmax, amax, tmax (nq,), fractions (F >= 1,)");
        check_gridpoints(gp, "spline_topp_ra");
        dmh::ChainDynamics dyn;
        bool torque = false;
        for (size_t j = 0; j < nq; ++j) torque |= std::isfinite(tmax.data()[j]);
        const int64_t kind = dmh::TORQUE;
        if (torque) kinds_need_dynamics(&kind, 1, (int64_t)nq, dyn_ints, dyn_floats, dyn);
        double* xs = new double[N1];
        int64_t stage;
        bool finite;
        {
            nb::gil_scoped_release unlocked;
            dmh::StageRowsOut rows;
            dmh::spline_stage_rows(sp, gp.data(), (int64_t)N1, vmax.data(), amax.data(), tmax.data(), phi.data(),
                                   (int64_t)phi.shape(0), velocity_bound, torque ? &dyn : nullptr, rows);
            finite = all_finite(rows.A.data(), rows.A.size()) && all_finite(rows.B.data(), rows.B.size()) &&
                     all_finite(rows.C.data(), rows.C.size());
            std::vector<double> K(2 * N1, NAN), us(N1, NAN);
            for (size_t i = 0; i < N1; ++i) xs[i] = NAN;
            if (finite)
                stage = dmh::topp_ra(gp.data(), (int64_t)N1, rows.A.data(), rows.B.data(), rows.C.data(), rows.R,
                                     rows.x_lo.data(), rows.x_hi.data(), K.data(), xs, us.data());
        }
        auto xs_out = owned(xs, {N1});
        if (!finite) throw nb::value_error("spline_topp_ra: the rows must be finite");
        return nb::make_tuple(stage, xs_out);
    }, "c"_a, "x"_a, "gridpoints"_a, "vmax"_a, "amax"_a, "tmax"_a, "fractions"_a, "velocity_bound"_a,
    "dyn_ints"_a.none() = nb::none(), "dyn_floats"_a.none() = nb::none(),
    "topp_ra on the rows of drake_mh.trajectories.toppra_solve.stage_rows(...).canonical() for a joint spline\n"
    "(scipy PPoly c, x) at the gridpoints and fractions (velocity, acceleration and torque rows where a limit is\n"
    "finite; torque by the packed dynamics): (stage, xs (N+1,)) as topp_ra's.");

    // the (entry, buffer) pair of drake_mh.scene.batch.CollisionModel.free_function's make_one:
    // entry(q, clearance, self_clearance, buffer), the checker as the buffer
    m.def("free_one", [](One q, double clearance, double self_clearance, dmh::CollisionChecker& checker) {
        return free_one(checker, q, clearance, self_clearance);
    }, "q"_a, "clearance"_a, "self_clearance"_a, "checker"_a, FREE_ONE);
}
