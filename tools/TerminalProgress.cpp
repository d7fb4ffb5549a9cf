#include "TerminalProgress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace regolith::tools {

TerminalProgress TerminalProgress::forStderr() {
  return TerminalProgress(::isatty(STDERR_FILENO) == 1);
}

TerminalProgress::~TerminalProgress() {
  if (open_) std::fputc('\n', stderr);
}

store::ProgressFn TerminalProgress::callback() {
  if (!enabled_) return {};
  return [this](double fraction, std::string_view what) { draw(fraction, what); };
}

void TerminalProgress::draw(double fraction, std::string_view what) {
  const auto now = std::chrono::steady_clock::now();
  const bool done = fraction >= 1.0 && what == "done";
  if (!done && open_ && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  constexpr int kWidth = 30;
  const double f = std::clamp(fraction, 0.0, 1.0);
  const auto filled = static_cast<int>(f * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : ' ';
  bar[kWidth] = '\0';
  // \33[K clears what a longer label left on the line.
  std::fprintf(stderr, "\r[%s] %3d%% %.*s\33[K", bar, static_cast<int>(f * 100.0),
               static_cast<int>(what.size()), what.data());
  open_ = true;
  if (done) {
    std::fputc('\n', stderr);
    open_ = false;
  }
  std::fflush(stderr);
}

}  // namespace regolith::tools
