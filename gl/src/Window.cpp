#include <regolith/core/Error.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/Window.hpp>

#include <GLFW/glfw3.h>

#include <atomic>
#include <string>

namespace regolith::gl {

namespace {

static_assert(keys::kSpace == GLFW_KEY_SPACE && keys::kEscape == GLFW_KEY_ESCAPE &&
              keys::kEnter == GLFW_KEY_ENTER && keys::kTab == GLFW_KEY_TAB &&
              keys::kBackspace == GLFW_KEY_BACKSPACE && keys::kRight == GLFW_KEY_RIGHT &&
              keys::kLeft == GLFW_KEY_LEFT && keys::kDown == GLFW_KEY_DOWN &&
              keys::kUp == GLFW_KEY_UP && keys::kPageUp == GLFW_KEY_PAGE_UP &&
              keys::kPageDown == GLFW_KEY_PAGE_DOWN && keys::kF1 == GLFW_KEY_F1 &&
              keys::kF12 == GLFW_KEY_F12 && keys::kLeftShift == GLFW_KEY_LEFT_SHIFT &&
              keys::kLeftControl == GLFW_KEY_LEFT_CONTROL && GLFW_KEY_A == 'A' &&
              GLFW_KEY_0 == '0');

std::atomic<bool> g_open{false};  // GLFW is process-wide: one Window at a time
std::string g_lastError;          // GLFW's error callback, read on the creating thread

Window& owner(GLFWwindow* w) { return *static_cast<Window*>(glfwGetWindowUserPointer(w)); }

}  // namespace

Window::Window(int width, int height, const std::string& title) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384) {
    throw InvalidArgument("gl::Window(): size " + std::to_string(width) + "x" +
                          std::to_string(height) + ", expected 1..16384 each");
  }
  if (g_open.exchange(true)) throw InvalidArgument("gl::Window(): a window is already open");
  glfwSetErrorCallback([](int, const char* what) { g_lastError = what; });
  if (glfwInit() == GLFW_FALSE) {
    g_open = false;
    throw GlError("gl::Window(): glfwInit() failed: " + g_lastError +
                  " (no display? run under xvfb-run for a virtual one)");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  GLFWwindow* w = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (w == nullptr) {
    glfwTerminate();
    g_open = false;
    throw GlError("gl::Window(): no OpenGL 4.5 core window: " + g_lastError);
  }
  window_ = w;
  glfwMakeContextCurrent(w);
  glfwSwapInterval(0);
  int fw = 0, ww = 0, h = 0;
  glfwGetFramebufferSize(w, &fw, &h);
  glfwGetWindowSize(w, &ww, &h);
  scale_ = ww > 0 ? static_cast<double>(fw) / ww : 1.0;
  glfwSetWindowUserPointer(w, this);
  glfwSetKeyCallback(w, [](GLFWwindow* win, int key, int, int action, int) {
    if (action == GLFW_REPEAT) return;
    owner(win).events_.push_back({WindowEvent::Type::Key, key, action == GLFW_PRESS, 0.0, 0.0});
  });
  glfwSetMouseButtonCallback(w, [](GLFWwindow* win, int button, int action, int) {
    owner(win).events_.push_back(
        {WindowEvent::Type::MouseButton, button, action == GLFW_PRESS, 0.0, 0.0});
  });
  glfwSetCursorPosCallback(w, [](GLFWwindow* win, double x, double y) {
    Window& self = owner(win);
    self.events_.push_back(
        {WindowEvent::Type::CursorMove, 0, false, x * self.scale_, y * self.scale_});
  });
  glfwSetScrollCallback(w, [](GLFWwindow* win, double dx, double dy) {
    owner(win).events_.push_back({WindowEvent::Type::Scroll, 0, false, dx, dy});
  });
}

Window::~Window() {
  glfwDestroyWindow(static_cast<GLFWwindow*>(window_));
  glfwTerminate();
  glfwSetErrorCallback(nullptr);
  g_open = false;
}

std::vector<WindowEvent> Window::poll() {
  glfwPollEvents();
  std::vector<WindowEvent> out;
  out.swap(events_);
  return out;
}

void Window::swap() { glfwSwapBuffers(static_cast<GLFWwindow*>(window_)); }

void Window::setSwapInterval(int interval) { glfwSwapInterval(interval); }

bool Window::shouldClose() const {
  return glfwWindowShouldClose(static_cast<GLFWwindow*>(window_)) == GLFW_TRUE;
}

void Window::requestClose() {
  glfwSetWindowShouldClose(static_cast<GLFWwindow*>(window_), GLFW_TRUE);
}

void Window::setTitle(const std::string& title) {
  glfwSetWindowTitle(static_cast<GLFWwindow*>(window_), title.c_str());
}

std::pair<int, int> Window::framebufferSize() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(static_cast<GLFWwindow*>(window_), &w, &h);
  return {w, h};
}

double Window::time() { return glfwGetTime(); }

}  // namespace regolith::gl
