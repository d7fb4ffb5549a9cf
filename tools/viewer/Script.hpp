#pragma once
// `regolith view --script FILE`: input events from a text file (docs/viewer.md, "Scripts").
#include <regolith/gl/Window.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace regolith::tools::viewer {

/// One frame of a script: the input events fed before it is drawn, and what to do after
/// it is drawn (pick, screenshot, quit).
struct ScriptStep {
  std::vector<gl::WindowEvent> events;
  enum class After { Nothing, Pick, Screenshot, Quit };
  After after = After::Nothing;
  double x = 0.0, y = 0.0;  ///< Pick: the pixel (window pixels, origin top-left)
  std::string file;         ///< Screenshot: the PNG
  std::size_t line = 0;     ///< the script line it came from
};

/// Parses a script: one command a line, '#' starts a comment.
///   wait N                  N frames with no input
///   key K                   press and release key K (A..Z, 0..9, TAB, SPACE, ESCAPE,
///                           ENTER, LEFT, RIGHT, UP, DOWN, PAGEUP, PAGEDOWN)
///   drag X0 Y0 X1 Y1 [left|right] [STEPS]
///                           press at (X0, Y0), move to (X1, Y1) in STEPS frames (default
///                           10), release
///   scroll DY [X Y]         wheel DY notches (positive: zoom in) with the cursor at (X, Y)
///   move X Y                the cursor to (X, Y)
///   pick X Y                pick at (X, Y) (printed, and shown in the HUD)
///   screenshot FILE         save the window's image as a PNG
///   quit                    end (the script's end does too)
/// Throws InvalidArgument naming the file, the line and the expectation for anything else.
std::vector<ScriptStep> parseScript(const std::string& path);

}  // namespace regolith::tools::viewer
