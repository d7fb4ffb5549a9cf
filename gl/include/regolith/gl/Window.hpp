#pragma once
/// \file
/// An on-screen window with an OpenGL 4.5 core context (GLFW), and its input as events.

#include <string>
#include <utility>
#include <vector>

namespace regolith::gl {

/// Key codes of WindowEvent::key: GLFW's values (letters and digits are their ASCII
/// upper-case codes, 'A', '1'), so this header needs no GLFW include. Window.cpp checks
/// each against GLFW's constant.
namespace keys {
inline constexpr int kSpace = 32, kEscape = 256, kEnter = 257, kTab = 258, kBackspace = 259,
                     kRight = 262, kLeft = 263, kDown = 264, kUp = 265, kPageUp = 266,
                     kPageDown = 267, kF1 = 290, kF12 = 301, kLeftShift = 340, kLeftControl = 341;
}  // namespace keys

/// One input event, in window coordinates (pixels, origin top-left, y down).
struct WindowEvent {
  enum class Type { Key, MouseButton, CursorMove, Scroll };
  Type type = Type::Key;
  int code =
      0;  ///< Key: a keys:: code or 'A'..'Z', '0'..'9'; MouseButton: 0 left, 1 right, 2 middle
  bool press = false;       ///< Key, MouseButton: pressed (true) or released
  double x = 0.0, y = 0.0;  ///< CursorMove: the cursor; Scroll: the offsets (y: wheel)
};

/// A GLFW window with an OpenGL 4.5 core profile context, current on the creating thread
/// from construction on. Its events queue up between poll() calls. The one owner of the
/// context and of GLFW itself: at most one Window exists at a time (GLFW is initialised
/// by the constructor and terminated by the destructor).
///
/// Framebuffer sizes are in pixels (they may differ from window sizes on HiDPI screens;
/// cursor positions are scaled to framebuffer pixels). Belongs to the thread that made
/// it (GLFW's rule). Not copyable, not movable.
class Window {
 public:
  /// Throws GlError if GLFW cannot start (no display: "glfwInit(): ...") or gives no 4.5
  /// core context; InvalidArgument for a size outside 1..16384 or a second Window.
  Window(int width, int height, const std::string& title);
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  ~Window();

  /// Processes pending window-system events and returns the input events since the last
  /// call, in order.
  std::vector<WindowEvent> poll();
  /// Shows the default framebuffer's back buffer.
  void swap();
  /// Vertical sync on (1) or off (0).
  void setSwapInterval(int interval);
  [[nodiscard]] bool shouldClose() const;
  void requestClose();
  void setTitle(const std::string& title);
  /// The default framebuffer's size in pixels (width, height).
  [[nodiscard]] std::pair<int, int> framebufferSize() const;
  /// Seconds since GLFW started (monotonic).
  [[nodiscard]] static double time();

 private:
  void* window_ = nullptr;  // GLFWwindow
  std::vector<WindowEvent> events_;
  double scale_ = 1.0;  // framebuffer pixels per window unit
};

}  // namespace regolith::gl
