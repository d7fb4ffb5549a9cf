#pragma once
/// \file
/// Error types shared by every Regolith module.
///
/// Three tiers (see docs/errors.md): programmer misuse is an assertion; bad data from
/// outside (a NaN coordinate, a lying label, a corrupt file) throws a type derived from
/// regolith::Error whose message starts with the operation and names the field and the
/// expectation; library errors (HDF5, GDAL) are translated into these at the boundary.

#include <stdexcept>
#include <string>

namespace regolith {

/// Base of every exception Regolith throws on bad input.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A caller-supplied value is unusable: NaN or infinite coordinates, negative spacing,
/// an empty grid, a radius that is not positive.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// A mathematically valid input for which the operation has no finite answer, for example
/// a polar stereographic projection evaluated at the pole opposite its centre.
class DomainError : public Error {
 public:
  using Error::Error;
};

}  // namespace regolith
