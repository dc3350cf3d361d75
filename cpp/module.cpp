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
#include "fk.hpp"
#include "kdtree.hpp"
#include "planner.hpp"

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
    m.doc() = "drake_mh's compiled core (C++): the sphere-model collision check, its forward kinematics, point clouds' k-d trees and rrt_connect's planner and certified motion check.";
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
        "X_WF (N, 4, 4) and (want_jac) J (N, 6, nq) of the frame at (ER, Ep) in moving frame anchor.");

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

    bind_planner(m);

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

    // the (entry, buffer) pair of drake_mh.scene.batch.CollisionModel.free_function's make_one:
    // entry(q, clearance, self_clearance, buffer), the checker as the buffer
    m.def("free_one", [](One q, double clearance, double self_clearance, dmh::CollisionChecker& checker) {
        return free_one(checker, q, clearance, self_clearance);
    }, "q"_a, "clearance"_a, "self_clearance"_a, "checker"_a, FREE_ONE);
}
