#pragma once
// What the fuzz targets of tests/fuzz share (docs/reliability.md, "Fuzzing"): a scratch file
// in memory-backed /dev/shm that holds the current input, and the rule that only
// regolith::Error may leave an API call.

#include <regolith/core/Error.hpp>

#include <hdf5.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace regolith::fuzz {

/// A file of this process under /dev/shm (else the temporary folder), removed at exit.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& name) {
    std::error_code ec;
    const std::filesystem::path shm = "/dev/shm";
    const std::filesystem::path dir =
        std::filesystem::is_directory(shm, ec) ? shm : std::filesystem::temp_directory_path();
    path_ = dir / ("regolith-fuzz-" + std::to_string(::getpid()) + "-" + name);
  }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }

  /// Replaces the file's content with the input.
  void write(const std::uint8_t* data, std::size_t size) const {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) {
      std::fprintf(stderr, "fuzz: cannot write %s\n", path_.c_str());
      std::abort();
    }
  }
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
};

/// Lets HDF5 keep the blocks it frees for reuse, without its default limits (64 KiB per free
/// list): every file open allocates a metadata cache of about 1 MiB, which otherwise goes
/// back to the system and comes back as fresh pages each time (under ASan, a new mapping per
/// open). Ten times the executions per second for the store targets; no change in behaviour.
inline void keepHdf5FreeLists() { H5set_free_list_limits(-1, -1, -1, -1, -1, -1); }

/// Whether every HDF5 global heap collection ("GCOL") in a file image is consistent: it lies
/// inside the image and its objects' sizes neither overrun it nor are zero. HDF5 1.10 trusts
/// them: a zero-size free-space entry loops forever and an oversized object reads out of
/// bounds inside H5HG_read (issue 17's variable-length string class, fixed apart by
/// writing fixed-length strings and bounding the reads of old stores). The store targets
/// skip inputs that fail this, so that the fuzzer keeps finding other things; their inputs
/// are in tests/fuzz/known/.
inline bool globalHeapsConsistent(const std::uint8_t* data, std::size_t size) {
  const auto u64 = [&](std::size_t at) {
    std::uint64_t v = 0;
    for (std::size_t k = 0; k < 8; ++k) v |= std::uint64_t{data[at + k]} << (8 * k);
    return v;
  };
  // memmem: libc's, not instrumented, so the scan costs the fuzzer nothing in coverage.
  for (const std::uint8_t* hit = data; size >= 16;) {
    hit = static_cast<const std::uint8_t*>(
        memmem(hit, size - static_cast<std::size_t>(hit - data), "GCOL", 4));
    if (hit == nullptr) break;
    const std::size_t at = static_cast<std::size_t>(hit - data);
    ++hit;
    if (at + 16 > size) break;
    const std::uint64_t length = u64(at + 8);
    if (length < 16 || length > size - at) return false;
    const std::size_t end = at + static_cast<std::size_t>(length);
    for (std::size_t p = at + 16; p + 16 <= end;) {
      const unsigned index = data[p] | (unsigned{data[p + 1]} << 8U);
      const std::uint64_t objectSize = u64(p + 8);
      if (objectSize > end - p) return false;
      const std::uint64_t need =
          index > 0 ? 16 + ((objectSize + 7) & ~std::uint64_t{7}) : objectSize;
      if (need == 0 || need > end - p) return false;
      p += static_cast<std::size_t>(need);
    }
  }
  return true;
}

/// Runs `body`, letting regolith::Error (bad input, reported clearly) pass; anything else it
/// throws reaches libFuzzer, which reports it as a crash (an uncaught exception).
template <class Body>
void expectOnlyRegolithErrors(Body&& body) {
  try {
    body();
  } catch (const regolith::Error&) {
  }
}

}  // namespace regolith::fuzz
