#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>
#include <regolith/core/Message.hpp>

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <system_error>

namespace regolith::core {

namespace fs = std::filesystem;

namespace {

/// stat(2) of `p` into `st`; 0 on success, else errno.
int statOf(const fs::path& p, struct stat& st) { return ::stat(p.c_str(), &st) == 0 ? 0 : errno; }

}  // namespace

std::optional<std::string> pathProblem(const fs::path& path) {
  struct stat st {};
  const int err = statOf(path, st);
  switch (err) {
    case 0: return std::nullopt;
    case ELOOP: return "symlink loop (too many levels of symbolic links)";
    case ENOTDIR: return "a part of the path is not a folder";
    case ENOENT: {
      std::error_code ec;
      if (fs::is_symlink(fs::symlink_status(path, ec))) {
        return "dangling symlink (its target " + fs::read_symlink(path, ec).string() +
               " does not exist)";
      }
      return "no such file";
    }
    default: return std::strerror(err);
  }
}

bool sameFile(const fs::path& a, const fs::path& b) {
  struct stat sa {};
  struct stat sb {};
  return statOf(a, sa) == 0 && statOf(b, sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

void refuseOverwritingInput(const fs::path& output, std::span<const fs::path> inputs,
                            std::string_view operation) {
  struct stat st {};
  const std::string out = output.string();
  if (statOf(output, st) == ELOOP) {
    throw IoError(format({operation, out, *pathProblem(output), {}, {}}));
  }
  for (const fs::path& input : inputs) {
    if (!sameFile(output, input)) continue;
    const std::string field = "output is the same file as the input " + input.string();
    throw InvalidArgument(
        format({operation, out, field, {}, "a file that is not one of the inputs"}));
  }
}

}  // namespace regolith::core
