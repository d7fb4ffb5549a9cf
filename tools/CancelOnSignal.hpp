#pragma once
// Ctrl-C (SIGINT) and SIGTERM cancel a long write cleanly: the handlers only set a flag that
// the writer polls (store::WriteOptions::cancel, store::ImportOptions::cancel); the writer then
// stops, removes its temporary file and throws, and the command exits non-zero.

#include <atomic>

namespace regolith::tools {

/// Installs the cancelling SIGINT/SIGTERM handlers for its lifetime (clearing the flag first),
/// then restores the default handlers. One at a time.
class CancelOnSignal {
 public:
  CancelOnSignal();
  ~CancelOnSignal();
  CancelOnSignal(const CancelOnSignal&) = delete;
  CancelOnSignal& operator=(const CancelOnSignal&) = delete;
  CancelOnSignal(CancelOnSignal&&) = delete;
  CancelOnSignal& operator=(CancelOnSignal&&) = delete;

  /// The flag the handlers set: pass it as the writer's `cancel` (valid for the program's
  /// lifetime, also before a CancelOnSignal exists).
  [[nodiscard]] static const std::atomic<bool>* flag() noexcept;
};

}  // namespace regolith::tools
