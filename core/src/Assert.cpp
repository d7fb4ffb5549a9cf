#include <regolith/core/Assert.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace regolith::core {

void assertionFailed(std::string_view file, int line, std::string_view condition,
                     std::string_view message) noexcept {
  // One write of the whole line, so that lines of two threads never interleave.
  std::string text = "regolith: assertion failed: ";
  text.append(file);
  text += ':';
  text += std::to_string(line);
  text += ": ";
  text.append(condition);
  if (!message.empty()) {
    text += ": ";
    text.append(message);
  }
  text += '\n';
  std::fwrite(text.data(), 1, text.size(), stderr);
  std::fflush(stderr);
  std::abort();
}

}  // namespace regolith::core
