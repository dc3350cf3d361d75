// Bindings of the cubic joint path (cubic_path.hpp) for drake_mh/trajectories/paths.py.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdint>

#include "cubic_path.hpp"

namespace dmh_bind {

namespace nb = nanobind;
using namespace nb::literals;

inline void bind_paths(nb::module_& m) {
    using Knots = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
    using Rows = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
    using Result = nb::ndarray<nb::numpy, double>;
    m.def("cubic_path", [](Knots s, Rows P) -> nb::object {
        const int64_t n = (int64_t)s.shape(0), nq = (int64_t)P.shape(1);
        if (n < 2 || (int64_t)P.shape(0) != n || nq < 1)
            throw nb::value_error("cubic_path: knots s (n >= 2,) and rows P (n, nq >= 1)");
        for (int64_t i = 0; i < n; ++i)
            if (!std::isfinite(s.data()[i]) || (i > 0 && !(s.data()[i] > s.data()[i - 1])))
                throw nb::value_error("cubic_path: the knots s must be finite and strictly increasing");
        for (int64_t i = 0; i < n * nq; ++i)
            if (!std::isfinite(P.data()[i])) throw nb::value_error("cubic_path: the rows P must be finite");
        const int64_t m_ = n - 1;
        double* c = new double[(size_t)(4 * m_ * nq)];
        double* lo = new double[(size_t)(m_ * nq)];
        double* hi = new double[(size_t)(m_ * nq)];
        auto own = [](double* p, std::initializer_list<size_t> shape) {
            nb::capsule owner(p, [](void* q) noexcept { delete[] static_cast<double*>(q); });
            return Result(p, shape, owner);
        };
        Result C = own(c, {4, (size_t)m_, (size_t)nq}), LO = own(lo, {(size_t)m_, (size_t)nq}),
               HI = own(hi, {(size_t)m_, (size_t)nq});
        bool ok;
        {
            nb::gil_scoped_release unlocked;
            ok = dmh::not_a_knot(s.data(), P.data(), n, nq, c);
            if (ok) dmh::piece_extrema(c, s.data(), m_, nq, lo, hi);
        }
        if (!ok) return nb::none();
        return nb::make_tuple(C, LO, HI);
    }, "s"_a, "P"_a,
    "(c (4, n - 1, nq), lo, hi (n - 1, nq)) of the not-a-knot cubic spline through P (n, nq) at the\n"
    "strictly increasing knots s (n,): scipy PPoly coefficients (highest power first) and each piece's\n"
    "exact minimum and maximum per joint; None where the slopes' system is singular.");
}

}  // namespace dmh_bind
