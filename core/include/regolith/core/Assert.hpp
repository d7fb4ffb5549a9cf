#pragma once
/// \file
/// Tier 1 of docs/errors.md: programmer misuse (an index out of range in an internal call, a
/// null pointer where the contract says non-null, an unknown enumerator) is a bug in the
/// caller, not bad data, so it is an assertion rather than an exception.
///
/// REGOLITH_ASSERT(condition, message) checks in debug builds (NDEBUG undefined) and in any
/// build compiled with REGOLITH_FORCE_ASSERTS defined (the CMake option of the same name turns
/// it on for every Regolith target). A failed assertion prints the file, the line, the
/// condition and the message to stderr and aborts. Otherwise the condition is not evaluated.

#include <string_view>

namespace regolith::core {

/// Prints "regolith: assertion failed: <file>:<line>: <condition>: <message>" to stderr and
/// calls std::abort(). Thread-safe (one write of the whole line).
[[noreturn]] void assertionFailed(std::string_view file, int line, std::string_view condition,
                                  std::string_view message) noexcept;

/// True in builds where REGOLITH_ASSERT checks (for tests that exercise a failing assertion).
inline constexpr bool kAssertionsEnabled =
#if !defined(NDEBUG) || defined(REGOLITH_FORCE_ASSERTS)
    true;
#else
    false;
#endif

}  // namespace regolith::core

#if !defined(NDEBUG) || defined(REGOLITH_FORCE_ASSERTS)
#define REGOLITH_ASSERT(condition, message) \
  ((condition) ? static_cast<void>(0)       \
               : ::regolith::core::assertionFailed(__FILE__, __LINE__, #condition, (message)))
#else
#define REGOLITH_ASSERT(condition, message) static_cast<void>(0)
#endif
