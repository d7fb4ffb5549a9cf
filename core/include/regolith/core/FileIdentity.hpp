#pragma once
/// \file
/// Which file a path names, for the checks every command and call that writes makes before
/// it starts: no output may be one of its inputs (writing it would replace the input), and
/// a path that cannot be opened is reported with the system's real reason (a symlink loop is
/// not "no such file").
///
/// Files are compared by device and inode (stat(2), which follows symlinks), so a symlink or
/// a hard link to an input is the input, whatever its name.
///
/// Thread-safety: pure functions of the file system's state.

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace regolith::core {

/// Why `path` cannot be opened, or nullopt if stat(2) succeeds: "no such file", "symlink
/// loop (too many levels of symbolic links)", "dangling symlink (its target <t> does not
/// exist)", "a part of the path is not a folder", or the system's reason.
[[nodiscard]] std::optional<std::string> pathProblem(const std::filesystem::path& path);

/// Whether `a` and `b` name one existing file (same device and inode, through symlinks and
/// hard links). False if either does not exist.
[[nodiscard]] bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b);

/// Throws InvalidArgument
///     `<operation>: <output>: output is the same file as the input <input>, expected a file
///     that is not one of the inputs`
/// if `output` names the same file as one of `inputs` (sameFile()). An output that does not
/// exist yet is fine; an input that does not exist is skipped (the operation reports it when
/// it opens it). Throws IoError `<operation>: <output>: symlink loop (...)` if the output is a
/// symlink loop.
void refuseOverwritingInput(const std::filesystem::path& output,
                            std::span<const std::filesystem::path> inputs,
                            std::string_view operation);

}  // namespace regolith::core
