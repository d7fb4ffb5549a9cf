#pragma once
/// \file
/// Error types shared by every Regolith module (tier 2 of docs/errors.md).
///
/// Three tiers: programmer misuse is an assertion (REGOLITH_ASSERT, regolith/core/Assert.hpp);
/// bad data from outside (a NaN coordinate, a lying label, a corrupt file) throws a type
/// derived from regolith::Error whose message starts with the operation and names the file,
/// the field, the value and the expectation (regolith/core/Message.hpp builds them); library
/// errors (HDF5, GDAL, the file system) are translated into these at the module boundary.
///
/// Thread-safety: exceptions are values; nothing here has state.

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

/// The file system refused an operation: a file that cannot be created, written, synced or
/// renamed (a full disk, a read-only folder). The message names the file and the system's
/// reason.
class IoError : public Error {
 public:
  using Error::Error;
};

}  // namespace regolith
