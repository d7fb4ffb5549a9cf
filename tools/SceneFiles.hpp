#pragma once
// Scene files (docs/scene-format.md) on the command line: `regolith info [--json] scene.json`
// and `regolith render scene.json --camera NAME -o x.png`.

#include <filesystem>
#include <ostream>
#include <string>

namespace regolith::tools {

/// True if `path` is a JSON file whose top-level object has a "bodies" key (a scene file;
/// a catalogue file has "datasets").
[[nodiscard]] bool isSceneFile(const std::filesystem::path& path);

/// Prints what a scene declares: bodies and their datasets, DEMs, objects, cameras and each
/// terrain's effects (as JSON with `json`).
void printSceneInfo(const std::filesystem::path& path, bool json, std::ostream& out);

/// Renders camera `camera` of a scene file to a PNG (`camera` empty: the scene's only camera).
/// Throws InvalidArgument naming the file and listing the cameras for a missing or unknown
/// camera, or if `png` would overwrite the scene or one of its stores.
void renderSceneFile(const std::filesystem::path& path, const std::string& camera,
                     const std::filesystem::path& png, std::ostream& report);

}  // namespace regolith::tools
