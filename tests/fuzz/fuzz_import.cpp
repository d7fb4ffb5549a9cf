// Fuzz target: the raster import (store::inspectRaster, then store::importRaster for small
// rasters) on files held in GDAL's /vsimem/, so that GDAL's drivers (GTiff, PDS3, PDS4,
// ISIS3, ...) parse fuzzed labels and data. Only regolith::Error may come out.
//
// One input holds one or more files (a PDS3 or PDS4 label and its data), in the container
// format of tests/fuzz/make_corpus.py:
//   <name of the raster>\n<its bytes>[\0@@FILE@@<name>\n<bytes>]...
// The first file is the one imported; names keep [A-Za-z0-9._-] only (others: f<k>).
// Rasters of more than 2^16 samples are inspected but not imported (time, not safety: a
// declared size is read in full).
#include <regolith/store/Import.hpp>

#include "FuzzSupport.hpp"

#include <cpl_vsi.h>
#include <gdal.h>

#include <string>
#include <string_view>
#include <vector>

namespace {

struct MemFile {
  std::string name;
  std::string_view bytes;
};

std::string cleanName(std::string_view name, std::size_t k) {
  std::string out;
  for (const char ch : name.substr(0, 64)) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                    (ch >= '0' && ch <= '9') || ch == '.' || ch == '_' || ch == '-';
    if (ok) out += ch;
  }
  if (out.empty() || out == "." || out == "..") out = "f" + std::to_string(k);
  return out;
}

std::vector<MemFile> split(std::string_view input) {
  constexpr std::string_view kMarker("\0@@FILE@@", 9);
  std::vector<MemFile> files;
  while (files.size() < 4) {
    const std::size_t eol = input.find('\n');
    const std::string_view name = input.substr(0, eol == std::string_view::npos ? 0 : eol);
    input.remove_prefix(eol == std::string_view::npos ? 0 : eol + 1);
    const std::size_t next = input.find(kMarker);
    files.push_back({cleanName(name, files.size()), input.substr(0, next)});
    if (next == std::string_view::npos) break;
    input.remove_prefix(next + kMarker.size());
  }
  return files;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const regolith::fuzz::ScratchFile store("import.h5");
  const std::vector<MemFile> files =
      split(std::string_view(reinterpret_cast<const char*>(data), size));
  const std::string dir = "/vsimem/regolith-fuzz/";
  for (const MemFile& f : files) {
    // GDAL reads the input where it is (FALSE: not owned, not copied); unlinked below.
    VSILFILE* fp = VSIFileFromMemBuffer((dir + f.name).c_str(),
                                        reinterpret_cast<GByte*>(const_cast<char*>(f.bytes.data())),
                                        static_cast<vsi_l_offset>(f.bytes.size()), FALSE);
    if (fp != nullptr) VSIFCloseL(fp);
  }
  const std::string raster = dir + files.front().name;
  regolith::fuzz::expectOnlyRegolithErrors([&] {
    regolith::store::ImportOptions options;
    options.patchRows = options.patchCols = 16;
    options.threads = 1;
    const regolith::store::ImportReport r = regolith::store::inspectRaster(raster, options);
    constexpr std::size_t kMaxSamples = std::size_t{1} << 16U;
    if (r.info.rows <= kMaxSamples && r.info.cols <= kMaxSamples &&
        r.info.rows * r.info.cols <= kMaxSamples) {
      (void)regolith::store::importRaster(raster, store.path(), options);
    }
  });
  for (const MemFile& f : files) VSIUnlink((dir + f.name).c_str());
  return 0;
}
