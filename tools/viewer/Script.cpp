#include "Script.hpp"

#include <regolith/core/Error.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace regolith::tools::viewer {

namespace {

using Event = gl::WindowEvent;

int keyCode(const std::string& name) {
  if (name.size() == 1 && std::isalnum(static_cast<unsigned char>(name[0])) != 0)
    return std::toupper(static_cast<unsigned char>(name[0]));
  static const std::map<std::string, int> named{
      {"TAB", gl::keys::kTab},       {"SPACE", gl::keys::kSpace},
      {"ESCAPE", gl::keys::kEscape}, {"ENTER", gl::keys::kEnter},
      {"LEFT", gl::keys::kLeft},     {"RIGHT", gl::keys::kRight},
      {"UP", gl::keys::kUp},         {"DOWN", gl::keys::kDown},
      {"PAGEUP", gl::keys::kPageUp}, {"PAGEDOWN", gl::keys::kPageDown}};
  std::string upper = name;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  const auto it = named.find(upper);
  return it == named.end() ? -1 : it->second;
}

}  // namespace

std::vector<ScriptStep> parseScript(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidArgument("view: --script " + path + ": cannot open the file");
  std::vector<ScriptStep> steps;
  std::string text;
  std::size_t lineNo = 0;
  while (std::getline(in, text)) {
    ++lineNo;
    if (const auto hash = text.find('#'); hash != std::string::npos) text.resize(hash);
    std::istringstream words(text);
    std::string command;
    if (!(words >> command)) continue;
    const auto fail = [&](const std::string& expected) {
      std::string message = "view: --script ";
      message += path;
      message += ":";
      message += std::to_string(lineNo);
      message += ": '";
      message += text;
      message += "': expected ";
      message += expected;
      return InvalidArgument(message);
    };
    const auto number = [&](const char* what) {
      double v = 0.0;
      if (!(words >> v) || !std::isfinite(v)) throw fail(std::string("a number for ") + what);
      return v;
    };
    const auto finish = [&] {
      std::string extra;
      if (words >> extra) throw fail("nothing after the command's arguments");
    };
    ScriptStep step;
    step.line = lineNo;
    if (command == "wait") {
      const double n = number("the frame count");
      if (n < 0 || n > 1e6 || n != std::floor(n)) throw fail("a whole number of frames, 0..1e6");
      finish();
      for (int i = 0; i < static_cast<int>(n); ++i) steps.push_back(step);
    } else if (command == "key") {
      std::string name;
      if (!(words >> name)) throw fail("a key name");
      const int code = keyCode(name);
      if (code < 0) throw fail("a key: A..Z, 0..9, TAB, SPACE, ESCAPE, ENTER or an arrow");
      finish();
      step.events = {{Event::Type::Key, code, true, 0, 0}, {Event::Type::Key, code, false, 0, 0}};
      steps.push_back(step);
    } else if (command == "drag") {
      const double x0 = number("X0"), y0 = number("Y0"), x1 = number("X1"), y1 = number("Y1");
      int button = 0, n = 10;
      std::string word;
      while (words >> word) {
        if (word == "left") {
          button = 0;
        } else if (word == "right") {
          button = 1;
        } else {
          try {
            n = std::stoi(word);
          } catch (const std::exception&) {
            throw fail("left, right or a step count after the coordinates");
          }
          if (n < 1 || n > 10000) throw fail("a step count in 1..10000");
        }
      }
      ScriptStep press = step;
      press.events = {{Event::Type::CursorMove, 0, false, x0, y0},
                      {Event::Type::MouseButton, button, true, 0, 0}};
      steps.push_back(press);
      for (int i = 1; i <= n; ++i) {
        ScriptStep s = step;
        const double t = static_cast<double>(i) / n;
        s.events = {{Event::Type::CursorMove, 0, false, x0 + t * (x1 - x0), y0 + t * (y1 - y0)}};
        if (i == n) s.events.push_back({Event::Type::MouseButton, button, false, 0, 0});
        steps.push_back(s);
      }
    } else if (command == "scroll") {
      const double dy = number("DY");
      double x = -1.0, y = -1.0;
      if (words >> x) {
        if (!(words >> y)) throw fail("X and Y after DY, or nothing");
        step.events.push_back({Event::Type::CursorMove, 0, false, x, y});
      }
      finish();
      step.events.push_back({Event::Type::Scroll, 0, false, 0.0, dy});
      steps.push_back(step);
    } else if (command == "move") {
      const double x = number("X"), y = number("Y");
      finish();
      step.events = {{Event::Type::CursorMove, 0, false, x, y}};
      steps.push_back(step);
    } else if (command == "pick") {
      step.x = number("X");
      step.y = number("Y");
      finish();
      step.events = {{Event::Type::CursorMove, 0, false, step.x, step.y}};
      step.after = ScriptStep::After::Pick;
      steps.push_back(step);
    } else if (command == "screenshot") {
      if (!(words >> step.file)) throw fail("a PNG file name");
      finish();
      step.after = ScriptStep::After::Screenshot;
      steps.push_back(step);
    } else if (command == "quit") {
      finish();
      step.after = ScriptStep::After::Quit;
      steps.push_back(step);
    } else {
      throw fail("one of wait, key, drag, scroll, move, pick, screenshot, quit");
    }
  }
  return steps;
}

}  // namespace regolith::tools::viewer
