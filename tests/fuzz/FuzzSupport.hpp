#pragma once
// What the fuzz targets of tests/fuzz share (docs/reliability.md, "Fuzzing"): a scratch file
// in memory-backed /dev/shm that holds the current input, and the rule that only
// regolith::Error may leave an API call.

#include <regolith/core/Error.hpp>

#include <fcntl.h>
#include <hdf5.h>
#include <pthread.h>
#include <sanitizer/common_interface_defs.h>
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

/// Lets a forked child of the fuzz process die quietly: since store format 1.4 the reader
/// reads an old store's variable-length strings in a child process
/// (hdf5::VariableStringBatch, readVariableStringBounded()), and HDF5 crashing there on a
/// damaged global heap is the child's purpose: the parent turns its exit status into a
/// StoreError. But the child inherits the sanitizers and libFuzzer: AddressSanitizer would
/// print its report into the fuzz log and call libFuzzer's death callback, which writes the
/// input as a crash-* artifact although the fuzz process itself never crashed (51 such
/// "crashes" in 62,339 runs of fuzz_store before this). In every child forked after this
/// call (the process forks nowhere else), a sanitizer's report goes to /dev/null and its
/// death ends the child with exit status 1, which the reader reports as "HDF5 crashed
/// reading it (exit status 1)". A crash of the fuzz process itself is reported as before.
inline void quietSanitizerDeathsInForkedChildren() {
  (void)pthread_atfork(nullptr, nullptr, [] {
    const int null = ::open("/dev/null", O_WRONLY);  // async-signal-safe, as is all of this
    if (null >= 0) __sanitizer_set_report_fd(reinterpret_cast<void*>(static_cast<intptr_t>(null)));
    __sanitizer_set_death_callback([] { ::_exit(1); });
  });
}

/// Whether HDF5 1.10 could loop forever parsing a global heap collection ("GCOL") of a file
/// image. Its parser (H5HG__cache_heap_deserialize) steps from one object to the next by the
/// object's recorded size, and an object whose step is 0 (a free-space object of size 0, or
/// a size that wraps the step to 0) keeps it in place forever; a step near 2^64 wraps the
/// pointer backwards. Bytes past the end of the file
/// read as zeros, which are such objects, so a collection that overruns the file counts too.
/// So do a collection or an object declared larger than 2 GiB: HDF5 may allocate that much,
/// and libFuzzer's malloc limit (2560 MB in scripts/fuzz.sh) would report an out-of-memory
/// of the target from the child (its malloc hook, unlike the death callback, cannot be
/// switched off there).
///
/// The store targets skip such inputs (issue 17's class of variable-length strings in the
/// global heap, tests/fuzz/known/). Every other damage to a global heap runs: the reader
/// reads an old store's variable-length strings in a child process, which absorbs HDF5's
/// crashes there (quietSanitizerDeathsInForkedChildren()), but a loop costs that child's
/// 10 s watchdog per input, which would leave the fuzzer a few executions per second
/// (docs/reliability.md, "Exclusions").
inline bool globalHeapMayLoop(const std::uint8_t* data, std::size_t size) {
  // Little-endian, zeros past the end of the input (as HDF5's sec2 driver reads them).
  const auto byteAt = [&](std::uint64_t at) -> std::uint64_t { return at < size ? data[at] : 0; };
  const auto u16 = [&](std::uint64_t at) { return byteAt(at) | (byteAt(at + 1) << 8U); };
  const auto u64 = [&](std::uint64_t at) {
    std::uint64_t v = 0;
    for (std::uint64_t k = 0; k < 8; ++k) v |= byteAt(at + k) << (8 * k);
    return v;
  };
  constexpr std::uint64_t kHeader = 16, kMaxLength = std::uint64_t{1} << 31U;
  // memmem: libc's, not instrumented, so the scan costs the fuzzer nothing in coverage.
  for (const std::uint8_t* hit = data; size >= kHeader;) {
    hit = static_cast<const std::uint8_t*>(
        memmem(hit, size - static_cast<std::size_t>(hit - data), "GCOL", 4));
    if (hit == nullptr) break;
    const std::uint64_t at = static_cast<std::uint64_t>(hit - data);
    ++hit;
    const std::uint64_t length = u64(at + 8);
    if (length > kMaxLength) return true;
    // HDF5's walk, in its own unsigned 64-bit arithmetic: an object header (index, references,
    // reserved, size) is 16 bytes; a numbered object's step is 16 + its size rounded up to 8,
    // the free-space object's (index 0) its size; a tail shorter than a header ends the walk.
    const std::uint64_t end = at + length;
    for (std::uint64_t p = at + kHeader; p < end && end - p >= kHeader;) {
      const std::uint64_t index = u16(p), objectSize = u64(p + 8);
      if (objectSize > kMaxLength) return true;
      const std::uint64_t step =
          index > 0 ? kHeader + ((objectSize + 7) & ~std::uint64_t{7}) : objectSize;
      // 0 stays in place; more than 2^62 moves HDF5's pointer backwards (it wraps).
      if (step == 0 || step > (std::uint64_t{1} << 62U)) return true;
      if (step >= end - p) break;  // past the collection: HDF5's walk ends
      p += step;
    }
  }
  return false;
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
