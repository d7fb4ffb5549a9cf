#include "Hud.hpp"

#include <regolith/gl/Gl.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <string_view>

namespace regolith::tools::viewer {

namespace {

// A hand-written 3×5 font. Why not a font library: the HUD needs ~50 glyphs at one size,
// and FreeType or stb_truetype would add a dependency, a font file to ship and a glyph
// atlas to manage for that; 50 five-row bitmaps are smaller than the code to load a font.
// Each glyph is five rows of three columns, '#' set.
struct Glyph {
  char c{};
  std::array<std::string_view, 5> rows;
};
constexpr std::array<Glyph, 56> kFont{{
    {'0', {"###", "#.#", "#.#", "#.#", "###"}}, {'1', {".#.", "##.", ".#.", ".#.", "###"}},
    {'2', {"###", "..#", "###", "#..", "###"}}, {'3', {"###", "..#", ".##", "..#", "###"}},
    {'4', {"#.#", "#.#", "###", "..#", "..#"}}, {'5', {"###", "#..", "###", "..#", "###"}},
    {'6', {"###", "#..", "###", "#.#", "###"}}, {'7', {"###", "..#", ".#.", ".#.", ".#."}},
    {'8', {"###", "#.#", "###", "#.#", "###"}}, {'9', {"###", "#.#", "###", "..#", "###"}},
    {'A', {".#.", "#.#", "###", "#.#", "#.#"}}, {'B', {"##.", "#.#", "##.", "#.#", "##."}},
    {'C', {".##", "#..", "#..", "#..", ".##"}}, {'D', {"##.", "#.#", "#.#", "#.#", "##."}},
    {'E', {"###", "#..", "##.", "#..", "###"}}, {'F', {"###", "#..", "##.", "#..", "#.."}},
    {'G', {".##", "#..", "#.#", "#.#", ".##"}}, {'H', {"#.#", "#.#", "###", "#.#", "#.#"}},
    {'I', {"###", ".#.", ".#.", ".#.", "###"}}, {'J', {"..#", "..#", "..#", "#.#", ".#."}},
    {'K', {"#.#", "#.#", "##.", "#.#", "#.#"}}, {'L', {"#..", "#..", "#..", "#..", "###"}},
    {'M', {"#.#", "###", "###", "#.#", "#.#"}}, {'N', {"##.", "#.#", "#.#", "#.#", "#.#"}},
    {'O', {".#.", "#.#", "#.#", "#.#", ".#."}}, {'P', {"##.", "#.#", "##.", "#..", "#.."}},
    {'Q', {".#.", "#.#", "#.#", "##.", ".##"}}, {'R', {"##.", "#.#", "##.", "#.#", "#.#"}},
    {'S', {".##", "#..", ".#.", "..#", "##."}}, {'T', {"###", ".#.", ".#.", ".#.", ".#."}},
    {'U', {"#.#", "#.#", "#.#", "#.#", "###"}}, {'V', {"#.#", "#.#", "#.#", "#.#", ".#."}},
    {'W', {"#.#", "#.#", "###", "###", "#.#"}}, {'X', {"#.#", "#.#", ".#.", "#.#", "#.#"}},
    {'Y', {"#.#", "#.#", ".#.", ".#.", ".#."}}, {'Z', {"###", "..#", ".#.", "#..", "###"}},
    {' ', {"...", "...", "...", "...", "..."}}, {'.', {"...", "...", "...", "...", ".#."}},
    {',', {"...", "...", "...", ".#.", "#.."}}, {':', {"...", ".#.", "...", ".#.", "..."}},
    {'-', {"...", "...", "###", "...", "..."}}, {'+', {"...", ".#.", "###", ".#.", "..."}},
    {'/', {"..#", "..#", ".#.", "#..", "#.."}}, {'%', {"#.#", "..#", ".#.", "#..", "#.#"}},
    {'(', {".#.", "#..", "#..", "#..", ".#."}}, {')', {".#.", "..#", "..#", "..#", ".#."}},
    {'[', {"##.", "#..", "#..", "#..", "##."}}, {']', {".##", "..#", "..#", "..#", ".##"}},
    {'=', {"...", "###", "...", "###", "..."}}, {'_', {"...", "...", "...", "...", "###"}},
    {'?', {"###", "..#", ".#.", "...", ".#."}}, {'<', {"..#", ".#.", "#..", ".#.", "..#"}},
    {'>', {"#..", ".#.", "..#", ".#.", "#.."}}, {'\'', {".#.", ".#.", "...", "...", "..."}},
    {'*', {"#.#", ".#.", "#.#", "...", "..."}}, {'|', {".#.", ".#.", ".#.", ".#.", ".#."}},
}};

const Glyph& glyph(char c) {
  const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kFont)
    if (g.c == u) return g;
  return glyph('?');
}

constexpr int kCellW = 4, kCellH = 7, kMargin = 2;  // font pixels per character, per line

}  // namespace

gl::RgbaImage renderText(const std::vector<std::string>& lines, int scale) {
  std::size_t longest = 0;
  for (const std::string& l : lines) longest = std::max(longest, l.size());
  gl::RgbaImage image;
  image.width = (static_cast<int>(longest) * kCellW + 2 * kMargin) * scale;
  image.height = (static_cast<int>(lines.size()) * kCellH + 2 * kMargin) * scale;
  image.rgba.assign(
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4, 0);
  for (std::size_t i = 3; i < image.rgba.size(); i += 4) {  // the dark box
    image.rgba[i - 3] = 10;
    image.rgba[i - 2] = 12;
    image.rgba[i - 1] = 20;
    image.rgba[i] = 255;
  }
  for (std::size_t li = 0; li < lines.size(); ++li) {
    for (std::size_t ci = 0; ci < lines[li].size(); ++ci) {
      const Glyph& g = glyph(lines[li][ci]);
      for (int r = 0; r < 5; ++r) {
        for (int c = 0; c < 3; ++c) {
          if (g.rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)] != '#') continue;
          const int x0 = (kMargin + static_cast<int>(ci) * kCellW + c) * scale;
          const int y0 = (kMargin + static_cast<int>(li) * kCellH + r + 1) * scale;
          for (int y = y0; y < y0 + scale; ++y) {
            for (int x = x0; x < x0 + scale; ++x) {
              std::uint8_t* p = image.rgba.data() + 4 * (static_cast<std::size_t>(y) *
                                                             static_cast<std::size_t>(image.width) +
                                                         static_cast<std::size_t>(x));
              p[0] = 235;
              p[1] = 240;
              p[2] = 200;
            }
          }
        }
      }
    }
  }
  return image;
}

void Hud::draw(const std::vector<std::string>& lines, const gl::RenderTarget& target) {
  if (lines.empty()) return;
  const gl::RgbaImage text = renderText(lines, 2);
  if (text.width != width_ || text.height != height_) {
    texture_ = gl::Texture();
    glTextureStorage2D(texture_.id(), 1, GL_RGBA8, text.width, text.height);
    framebuffer_ = gl::Framebuffer();
    glNamedFramebufferTexture(framebuffer_.id(), GL_COLOR_ATTACHMENT0, texture_.id(), 0);
    width_ = text.width;
    height_ = text.height;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(texture_.id(), 0, 0, 0, text.width, text.height, GL_RGBA, GL_UNSIGNED_BYTE,
                      text.rgba.data());
  // Image row 0 (the top) is GL row 0 (the bottom) of the texture: flip in the blit.
  const int w = std::min(text.width, target.width()), h = std::min(text.height, target.height());
  const int top = target.height();
  glBlitNamedFramebuffer(framebuffer_.id(), target.framebuffer(), 0, 0, w, h, 0, top, w, top - h,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace regolith::tools::viewer
