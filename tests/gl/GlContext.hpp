#pragma once
// The one headless GL context the clod GL tests share, and PNG output for people to look at.

#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/Image.hpp>

#include <cstdlib>
#include <string>

namespace regolith::test {

/// Creates the shared EGL surfaceless context on first use and keeps it current.
///
/// It is never destroyed: eglTerminate() at exit would unload Mesa's driver before
/// LeakSanitizer runs, and the driver's process-lifetime allocations would then be reported
/// from an "<unknown module>" that no suppression can name (tests/clod/lsan.supp names the
/// driver libraries, which stay loaded this way). The pointer stays reachable, so the
/// context itself is not reported.
inline gl::HeadlessContext& glContext() {
  static gl::HeadlessContext* const context = new gl::HeadlessContext();
  context->makeCurrent();
  return *context;
}

/// Writes `image` to $REGOLITH_TEST_PNG_DIR/<name>.png if that variable is set.
inline void savePng(const std::string& name, const gl::RgbaImage& image) {
  const char* dir = std::getenv("REGOLITH_TEST_PNG_DIR");
  if (dir == nullptr || *dir == '\0') return;
  gl::writePng(std::string(dir) + "/" + name + ".png", image);
}

}  // namespace regolith::test
