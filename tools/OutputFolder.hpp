#pragma once
// Checks every command makes on its outputs before doing any work (a long import or
// generation should not fail at the very end, and must never replace one of its inputs).

#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

namespace regolith::tools {

/// Throws InvalidArgument "<command>: --out <out>: folder <dir> does not exist" unless the
/// folder of `out` (the current folder for a bare name) is an existing directory, and
/// IoError "<command>: <out>: symlink loop (...)" if `out` is a symlink loop.
void requireOutputFolder(std::string_view command, const std::string& out);

/// For commands whose --out names a folder they create (`demo`, `walkthrough`): throws
/// IoError if `dir` is a symlink loop, InvalidArgument if it is an existing file, before any
/// work.
void requireFolderToWrite(std::string_view command, const std::string& dir);

/// core::refuseOverwritingInput() for each of `outputs` against all of `inputs`: throws
/// InvalidArgument if an output is the same file as an input (through symlinks and hard
/// links).
void refuseOverwritingInputs(std::string_view command,
                             std::initializer_list<std::filesystem::path> outputs,
                             std::initializer_list<std::filesystem::path> inputs);

/// The same for standard output (`regolith info s.h5 >> s.h5` would write into the store it
/// reads): throws InvalidArgument if stdout is the file `input`.
void refuseStdoutOverInput(std::string_view command, const std::filesystem::path& input);

}  // namespace regolith::tools
