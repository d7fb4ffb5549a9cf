#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/Legend.hpp>
#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace regolith::clod {

namespace {

constexpr int kScale = 2;  // font pixels per glyph pixel
constexpr int kPad = 8;
constexpr int kBarW = 16, kBarH = 128;
constexpr int kLine = 7 * kScale;  // text line height

// 3 × 5 glyphs, one string of 15 '#'/'.' per glyph, rows top to bottom.
const char* glyph(char c) {
  switch (c) {
    case '0': return "####.##.##.####";
    case '1': return ".#.##..#..#.###";
    case '2': return "###..#####..###";
    case '3': return "###..####..####";
    case '4': return "#.##.####..#..#";
    case '5': return "####..###..####";
    case '6': return "####..####.####";
    case '7': return "###..#..#..#..#";
    case '8': return "####.#####.####";
    case '9': return "####.####..####";
    case '-': return "......###......";
    case '.': return ".............#.";
    case '/': return "..#..#.#..#.#..";
    case 'A': return "####.#####.##.#";
    case 'L': return "#..#..#..#..###";
    case 'M': return "#.########.##.#";
    case 'N': return "####.##.##.##.#";
    case 'O': return "####.##.##.####";
    case 'T': return "###.#..#..#..#.";
    case 'o': return "####.####......";
    default: return "...............";
  }
}

void put(gl::RgbaImage& img, int x, int y, std::array<std::uint8_t, 4> c) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  auto* p =
      img.rgba.data() + 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                             static_cast<std::size_t>(x));
  std::copy(c.begin(), c.end(), p);
}

void text(gl::RgbaImage& img, int x, int y, const std::string& s) {
  for (char ch : s) {
    const char* g = glyph(ch);
    for (int r = 0; r < 5; ++r)
      for (int c = 0; c < 3; ++c)
        if (g[r * 3 + c] == '#')
          for (int dy = 0; dy < kScale; ++dy)
            for (int dx = 0; dx < kScale; ++dx)
              put(img, x + c * kScale + dx, y + r * kScale + dy, {235, 235, 235, 255});
    x += 4 * kScale;
  }
}

std::string number(double v) {
  char buf[32];
  if (std::abs(v) >= 100.0 || v == std::round(v))
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else
    std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

/// JSON numbers: the shortest text that reads back as the same double (exact).
std::string exact(double v) { return core::number(v); }

std::uint8_t unorm8(float v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0F, 1.0F) * 255.0F));
}

}  // namespace

Legend::Legend(std::optional<HeightColours> heights, std::optional<double> latLonSpacingDegrees)
    : heights_(heights), latLon_(latLonSpacingDegrees) {}

Legend Legend::of(const ClipmapTerrain& terrain, const Camera& camera) {
  const Effects& e = terrain.options().effects;
  std::optional<double> spacing;
  if (e.latLon) spacing = terrain.latLonSpacing(camera);
  return Legend(e.heightColours, spacing);
}

Legend::Bar Legend::bar() const noexcept {
  if (!heights_) return {};
  return {kPad, kPad, kPad + kBarW, kPad + kBarH};
}

double Legend::heightAtRow(int y) const {
  if (!heights_) throw InvalidArgument("Legend::heightAtRow(): the legend has no height bar");
  const Bar b = bar();
  const double t = (static_cast<double>(b.y1 - y) - 0.5) / static_cast<double>(b.y1 - b.y0);
  return static_cast<double>(heights_->minHeight) +
         t * static_cast<double>(heights_->maxHeight - heights_->minHeight);
}

gl::RgbaImage Legend::image() const {
  gl::RgbaImage img;
  if (empty()) {
    img.width = img.height = 1;
    img.rgba.assign(4, 0);
    return img;
  }
  img.width = 150;
  img.height = kPad + (heights_ ? kBarH + kPad : 0) + (latLon_ ? kLine + kPad : 0);
  img.rgba.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 4);
  for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
    img.rgba[i] = img.rgba[i + 1] = 20;
    img.rgba[i + 2] = 28;
    img.rgba[i + 3] = 255;
  }
  int y = kPad;
  if (heights_) {
    const Bar b = bar();
    for (int r = b.y0; r < b.y1; ++r) {
      const glm::vec3 c = heightColour(*heights_, heightAtRow(r));
      for (int x = b.x0; x < b.x1; ++x)
        put(img, x, r, {unorm8(c.r), unorm8(c.g), unorm8(c.b), 255});
    }
    const int tx = b.x1 + 6;
    text(img, tx, b.y0, number(static_cast<double>(heights_->maxHeight)) + " M");
    text(img, tx, (b.y0 + b.y1) / 2 - 5,
         number(0.5 * static_cast<double>(heights_->minHeight + heights_->maxHeight)) + " M");
    text(img, tx, b.y1 - 10, number(static_cast<double>(heights_->minHeight)) + " M");
    y = b.y1 + kPad;
  }
  if (latLon_) text(img, kPad, y, "LAT/LON " + number(*latLon_) + "o");
  return img;
}

void Legend::drawInto(gl::RgbaImage& target) const {
  if (empty()) return;
  const gl::RgbaImage img = image();
  const int x0 = target.width - img.width - 8, y0 = 8;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto* p = img.pixel(x, y);
      put(target, x0 + x, y0 + y, {p[0], p[1], p[2], p[3]});
    }
}

std::string Legend::json() const {
  std::string s = "{";
  if (heights_) {
    s += "\"heightColours\": {\"min\": " + exact(static_cast<double>(heights_->minHeight)) +
         ", \"max\": " + exact(static_cast<double>(heights_->maxHeight)) + ", \"stops\": [";
    for (std::size_t k = 0; k < kHeightRamp.size(); ++k) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%s[%.9g, %.9g, %.9g]", k ? ", " : "",
                    static_cast<double>(kHeightRamp[k].r), static_cast<double>(kHeightRamp[k].g),
                    static_cast<double>(kHeightRamp[k].b));
      s += buf;
    }
    s += "]}";
  }
  if (latLon_) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s\"latLonSpacingDegrees\": %.17g", heights_ ? ", " : "",
                  *latLon_);
    s += buf;
  }
  return s + "}\n";
}

void Legend::writeJson(const std::string& path) const {
  core::writeStreamAtomically(
      path, [this](std::ostream& out) { out << json(); }, "Legend::writeJson()");
}

}  // namespace regolith::clod
