#include "OutputFolder.hpp"

#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>

#include <span>
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
  core::refuseOverwritingInput(out, {}, command);  // names a symlink loop
}

void requireFolderToWrite(std::string_view command, const std::string& dir) {
  core::refuseOverwritingInput(dir, {}, command);  // names a symlink loop
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw InvalidArgument(std::string(command) + ": --out " + dir +
                          " is a file, expected a folder (created if it does not exist)");
  }
}

void refuseOverwritingInputs(std::string_view command,
                             std::initializer_list<std::filesystem::path> outputs,
                             std::initializer_list<std::filesystem::path> inputs) {
  const std::span<const std::filesystem::path> in(inputs.begin(), inputs.size());
  for (const auto& out : outputs) core::refuseOverwritingInput(out, in, command);
}

void refuseStdoutOverInput(std::string_view command, const std::filesystem::path& input) {
  // /dev/stdout is /proc/self/fd/1: stat() follows it to the file the shell opened.
  if (core::sameFile("/dev/stdout", input)) {
    throw InvalidArgument(std::string(command) + ": standard output is the input " +
                          input.string() + ", expected another file (writing to it would " +
                          "destroy the input)");
  }
}

}  // namespace regolith::tools
