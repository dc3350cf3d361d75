// The packed buffers of a Python call borrowed by a model (packed.hpp Buffers): the arrays are
// kept alive, not copied, while any model built from them lives.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <memory>

#include "packed.hpp"

namespace dmh {

template <class IntsArray, class FloatsArray>
inline Buffers borrow(const IntsArray& ints, const FloatsArray& floats) {
    struct Held {
        IntsArray ints;
        FloatsArray floats;
    };
    Buffers b;
    b.ints = ints.data(), b.n_ints = (int64_t)ints.shape(0);
    b.floats = floats.data(), b.n_floats = (int64_t)floats.shape(0);
    b.owner = std::shared_ptr<const void>(new Held{ints, floats}, [](const void* p) {
        nanobind::gil_scoped_acquire locked;  // the arrays' references are Python's
        delete static_cast<const Held*>(p);
    });
    return b;
}

}  // namespace dmh
