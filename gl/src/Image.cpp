#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Image.hpp>

#include <png.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace regolith::gl {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const noexcept { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void pngError(png_structp png, png_const_charp message) {
  auto* what = static_cast<std::string*>(png_get_error_ptr(png));
  *what = message;
  png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

// libpng reports errors by longjmp; these functions hold no C++ objects with destructors
// between setjmp and the calls that may jump.
bool encode(std::FILE* f, const RgbaImage& image, std::string& error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, pngError, pngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.height));
  for (int y = 0; y < image.height; ++y)
    rows[static_cast<std::size_t>(y)] = const_cast<png_bytep>(image.pixel(0, y));
  bool ok = false;
  if (info != nullptr && setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, f);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
                 static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB_ALPHA,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_rows(png, info, rows.data());
    png_write_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
    ok = true;
  }
  png_destroy_write_struct(&png, &info);
  return ok;
}

bool decode(std::FILE* f, RgbaImage& image, std::string& error) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, pngError, pngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  bool ok = false;
  if (info != nullptr && setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, f);
    png_read_png(png, info, PNG_TRANSFORM_STRIP_16 | PNG_TRANSFORM_PACKING | PNG_TRANSFORM_EXPAND,
                 nullptr);
    const auto w = png_get_image_width(png, info);
    const auto h = png_get_image_height(png, info);
    const auto channels = png_get_channels(png, info);
    if (channels == 3 || channels == 4) {
      png_bytepp rows = png_get_rows(png, info);
      image.width = static_cast<int>(w);
      image.height = static_cast<int>(h);
      image.rgba.assign(static_cast<std::size_t>(w) * h * 4, 255);
      for (png_uint_32 y = 0; y < h; ++y)
        for (png_uint_32 x = 0; x < w; ++x)
          for (png_uint_32 c = 0; c < channels; ++c)
            image.rgba[(static_cast<std::size_t>(y) * w + x) * 4 + c] = rows[y][x * channels + c];
      ok = true;
    } else {
      error = "expected an RGB or RGBA image, found " + std::to_string(channels) + " channels";
    }
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return ok;
}

}  // namespace

void writePng(const std::string& path, const RgbaImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() !=
          static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4)
    throw InvalidArgument("writePng(): " + path + ": image is " + std::to_string(image.width) +
                          " x " + std::to_string(image.height) + " with " +
                          std::to_string(image.rgba.size()) + " bytes, expected width·height·4");
  core::writeFileAtomically(
      path,
      [&](const std::filesystem::path& tmp) {
        File f(std::fopen(tmp.c_str(), "wb"));
        if (!f)
          throw IoError("writePng(): " + tmp.string() +
                        ": cannot open for writing: " + std::strerror(errno));
        std::string error = "libpng failed";
        if (!encode(f.get(), image, error)) throw IoError("writePng(): " + path + ": " + error);
        if (std::fflush(f.get()) != 0)
          throw IoError("writePng(): " + path + ": write failed: " + std::strerror(errno));
        if (std::fclose(f.release()) != 0)
          throw IoError("writePng(): " + path + ": write failed: " + std::strerror(errno));
      },
      "writePng()");
}

RgbaImage readPng(const std::string& path) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) throw Error("readPng(): " + path + ": cannot open: " + std::strerror(errno));
  RgbaImage image;
  std::string error = "not a PNG file";
  if (!decode(f.get(), image, error)) throw Error("readPng(): " + path + ": " + error);
  return image;
}

}  // namespace regolith::gl
