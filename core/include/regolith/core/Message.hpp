#pragma once
/// \file
/// The one way Regolith words a tier-2 error message (docs/errors.md):
///
///     <operation>: <file>: <field> is <value>, expected <expectation>
///
/// for example `store::open(): /data/x.h5: grid 'victoria' spacing is -1 m, expected > 0`.
/// Numbers are written by core::number(): the shortest text that reads back as the same
/// double (std::to_chars), so 1e-9 reads "1e-09", never "0.000000" as std::to_string prints it.
///
/// Thread-safety: pure functions.

#include <concepts>
#include <string>
#include <string_view>

namespace regolith::core {

/// The shortest decimal text that parses back to exactly `v` (std::to_chars); "nan", "inf"
/// and "-inf" for the non-finite values. 0.1 gives "0.1", 3396190.0 gives "3396190", 1e-9
/// gives "1e-09".
[[nodiscard]] std::string number(double v);

/// As number(double), with the shortest text that parses back to the same float.
[[nodiscard]] std::string number(float v);

/// An integer in decimal.
template <std::integral T>
[[nodiscard]] std::string number(T v) {
  return std::to_string(v);
}

/// The parts of a message. Empty parts are left out with their separators: without a file,
/// `<operation>: <field> is <value>, expected <expectation>`; without a value,
/// `<operation>: <file>: <field>, expected <expectation>`; without an expectation, no
/// `, expected` clause.
struct Message {
  std::string_view operation{};  ///< the public call that failed, with "()": "store::open()"
  std::string_view file{};       ///< the file it was working on, or empty
  std::string_view field{};      ///< what is wrong: "grid 'victoria' spacing", "latitude"
  std::string_view value{};      ///< the value found, with its unit: number(v) + " m"
  std::string_view expected{};   ///< what would have been right: "> 0", "finite"
};

/// The message text of `m`.
[[nodiscard]] std::string format(const Message& m);

}  // namespace regolith::core
