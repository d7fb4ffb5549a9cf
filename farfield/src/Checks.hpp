#pragma once
// Option checks shared by the far field's constructors.

#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <string>

namespace regolith::farfield::detail {

/// Throws InvalidArgument naming `operation` and `field` unless lo ≤ v ≤ hi.
inline void requireRange(const char* operation, const char* field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    const std::string value = core::number(v);
    const std::string expected = "in [" + core::number(lo) + ", " + core::number(hi) + "]";
    throw InvalidArgument(core::format(
        {.operation = operation, .field = field, .value = value, .expected = expected}));
  }
}

}  // namespace regolith::farfield::detail
