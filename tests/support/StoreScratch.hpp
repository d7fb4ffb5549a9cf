#pragma once
// Helpers shared by the store tests: scratch files that disappear with the test process, and
// a grid's level 0 read back whole.

#include <regolith/store/Store.hpp>

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace regolith::test {

/// `<tmp>/regolith-tests-<pid>/<suite>/<name>`; the folder is removed when the test process
/// exits normally.
inline std::filesystem::path scratchFile(const std::string& suite, const std::string& name) {
  namespace fs = std::filesystem;
  struct Dir {
    fs::path path = fs::temp_directory_path() / ("regolith-tests-" + std::to_string(::getpid()));
    Dir() = default;
    Dir(const Dir&) = delete;
    Dir& operator=(const Dir&) = delete;
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Dir dir;
  fs::create_directories(dir.path / suite);
  return dir.path / suite / name;
}

/// Level 0 of a grid, read with Store::readWindow (row-major, heights in metres).
inline std::vector<float> readLevel0(const std::filesystem::path& path, const std::string& grid) {
  const store::Store s = store::Store::open(path);
  const store::GridInfo& info = s.grid(grid);
  std::vector<float> v(info.rows * info.cols);
  s.readWindow(grid, 0, 0, 0, info.rows, info.cols, v);
  return v;
}

}  // namespace regolith::test
