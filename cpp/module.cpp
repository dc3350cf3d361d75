// drake_mh._native: the compiled core's entry points from Python (nanobind).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "collision.hpp"
#include "dynamics.hpp"
#include "fk.hpp"
#include "kdtree.hpp"

namespace nb = nanobind;
using namespace nb::literals;

using Ints = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Floats = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Batch = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using One = nb::ndarray<const double, nb::ndim<1>, nb::device::cpu>;
using BoolOut = nb::ndarray<nb::numpy, bool, nb::ndim<1>>;

static void init_checker(dmh::CollisionChecker* self, Ints ints, Floats floats) {
    new (self) dmh::CollisionChecker(std::vector<int64_t>(ints.data(), ints.data() + ints.shape(0)),
                                     std::vector<double>(floats.data(), floats.data() + floats.shape(0)));
    if (!self->ok()) {
        self->~CollisionChecker();
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

static const char* FREE_ONE =
    "One configuration q (nq,) float64 (any stride): 1 free, 0 not, -1 not finite, -2 a clearance\n"
    "not in [0, inf), -3 a wrong size.";

NB_MODULE(_native, m) {
    m.doc() = "drake_mh's compiled core (C++): the sphere-model collision check, its forward kinematics and point clouds' k-d trees.";
    m.attr("simd_width") = dmh::W;
    m.attr("lanes") = dmh::CollisionChecker::LANES;

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
        .def("__init__", &init_checker, "ints"_a, "floats"_a)
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

    m.def("kd_build", [](Points P) {
        const size_t N = P.shape(0);
        const double* p = P.data();
        for (size_t j = 0; j < 3 * N; ++j)
            if (!std::isfinite(p[j])) throw nb::value_error("kd_build: the points must be finite");
        int64_t* order = new int64_t[N + 1];
        int64_t* axes = new int64_t[N + 1];
        double* tree = new double[3 * N + 1];
        double* boxes = new double[6 * N + 1];
        {
            nb::gil_scoped_release unlocked;
            dmh::kd_build(p, (int64_t)N, order, axes, tree, boxes);
        }
        return nb::make_tuple(owned(order, {N}), owned(axes, {N}), owned(tree, {N, 3}), owned(boxes, {N, 6}));
    }, "P"_a,
    "(order (N,), axes (N,), tree (N, 3), boxes (N, 6)) of finite points P (N, 3) C-contiguous float64:\n"
    "the implicit k-d tree of drake_mh.scene.kernels.pieces.kd_build, the same tree (the same selection).");

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

    // the (entry, buffer) pair of drake_mh.scene.batch.CollisionModel.free_function's make_one:
    // entry(q, clearance, self_clearance, buffer), the checker as the buffer
    m.def("free_one", [](One q, double clearance, double self_clearance, dmh::CollisionChecker& checker) {
        return free_one(checker, q, clearance, self_clearance);
    }, "q"_a, "clearance"_a, "self_clearance"_a, "checker"_a, FREE_ONE);
}
