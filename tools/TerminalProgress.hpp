#pragma once
// A progress bar for long writes, drawn on stderr only when stderr is a terminal.

#include <regolith/store/Store.hpp>

#include <chrono>
#include <string>

namespace regolith::tools {

/// Makes store::ProgressFn callbacks that redraw one line on stderr ("\r[####    ] 42% what"),
/// at most ten times a second, and end it with a newline when the work is done. When stderr
/// is not a terminal (a pipe, a file, a test), the callbacks print nothing.
class TerminalProgress {
 public:
  /// `enabled`: draw at all (normally isatty(stderr)); see forStderr().
  explicit TerminalProgress(bool enabled) : enabled_(enabled) {}
  /// Enabled iff stderr is a terminal.
  [[nodiscard]] static TerminalProgress forStderr();
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;
  TerminalProgress(TerminalProgress&&) = delete;
  TerminalProgress& operator=(TerminalProgress&&) = delete;
  /// Ends an unfinished line (after an error).
  ~TerminalProgress();

  /// A callback drawing into this bar; valid while the bar lives.
  [[nodiscard]] store::ProgressFn callback();

 private:
  void draw(double fraction, std::string_view what);

  bool enabled_;
  bool open_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace regolith::tools
