#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

namespace regolith::core {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(std::string_view operation, const fs::path& file, const std::string& why) {
  throw IoError(std::string(operation) + ": " + file.string() + ": " + why);
}

/// fsync() of a file, or of a folder's entries.
void syncPath(const fs::path& p, bool directory, std::string_view operation) {
  const int fd = ::open(p.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) fail(operation, p, std::string("cannot open it to sync it: ") + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) fail(operation, p, std::string("cannot sync it: ") + std::strerror(err));
}

/// Removes the temporary unless the write committed it.
class Temporary {
 public:
  explicit Temporary(fs::path p) : path_(std::move(p)) {}
  ~Temporary() {
    if (!committed_) {
      std::error_code ignore;
      fs::remove(path_, ignore);
    }
  }
  Temporary(const Temporary&) = delete;
  Temporary& operator=(const Temporary&) = delete;
  Temporary(Temporary&&) = delete;
  Temporary& operator=(Temporary&&) = delete;
  [[nodiscard]] const fs::path& path() const noexcept { return path_; }
  void commit() noexcept { committed_ = true; }

 private:
  fs::path path_;
  bool committed_ = false;
};

}  // namespace

void syncFile(const fs::path& file, std::string_view operation) {
  syncPath(file, false, operation);
}

fs::path temporaryPathFor(const fs::path& target) {
  static std::atomic<unsigned long long> counter{0};
  return target.string() + ".tmp-" + std::to_string(::getpid()) + "-" +
         std::to_string(counter.fetch_add(1));
}

void writeFileAtomically(const fs::path& target, const std::function<void(const fs::path&)>& write,
                         std::string_view operation, Durability durability) {
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  // The folder must exist: a typo in a path is an error, not a new folder.
  if (!fs::exists(dir, ec))
    fail(operation, target, "the folder " + dir.string() + " does not exist");
  if (!fs::is_directory(dir, ec)) fail(operation, target, dir.string() + " is not a folder");
  Temporary tmp(temporaryPathFor(target));
  write(tmp.path());
  if (!fs::exists(tmp.path(), ec)) {
    fail(operation, tmp.path(), "the writer did not create the temporary file");
  }
  // Durable before visible: the data reach the disk, then the rename publishes them, then the
  // folder entry itself is synced. A scratch file is only renamed.
  const bool durable = durability == Durability::Durable;
  if (durable) syncPath(tmp.path(), false, operation);
  fs::rename(tmp.path(), target, ec);
  if (ec)
    fail(operation, target,
         "cannot rename " + tmp.path().string() + " into place: " + ec.message());
  tmp.commit();
  if (durable) syncPath(dir, true, operation);
}

void writeStreamAtomically(const fs::path& target, const std::function<void(std::ostream&)>& write,
                           std::string_view operation) {
  writeFileAtomically(
      target,
      [&](const fs::path& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out)
          fail(operation, tmp, std::string("cannot create the file: ") + std::strerror(errno));
        write(out);
        out.close();
        if (!out) fail(operation, target, "write failed (disk full?)");
      },
      operation);
}

}  // namespace regolith::core
