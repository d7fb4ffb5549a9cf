#include "OutputFolder.hpp"

#include <regolith/core/Error.hpp>

#include <filesystem>
#include <system_error>

namespace regolith::tools {

void requireOutputFolder(std::string_view command, const std::string& out) {
  std::filesystem::path dir = std::filesystem::path(out).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw InvalidArgument(std::string(command) + ": --out " + out + ": folder " + dir.string() +
                          " does not exist");
  }
}

}  // namespace regolith::tools
