#pragma once
// The subcommands of `regolith`. Each add*Command() registers one subcommand on the app,
// with its options and a callback that runs it. A callback reports failure by throwing
// (regolith::Error and its kin for bad input, CLI::Error for usage errors); main() turns
// that into "regolith: error: ..." on stderr and a non-zero exit code.

#include <filesystem>
#include <iosfwd>
#include <ostream>
#include <string>

namespace CLI {
class App;
}  // namespace CLI

namespace regolith::tools {

/// Help of the --compression option of `import` and `generate`.
inline constexpr const char* kCompressionHelp =
    "Chunk compression: deflate (HDF5's shuffle + deflate at --deflate; every HDF5 reader "
    "decodes it) or zfp (ZFP reversible, lossless: about 14% smaller, slower to read; "
    "readers need HDF5's ZFP filter plugin, Debian hdf5-filter-plugin-zfp-serial)";

void addDemoCommand(CLI::App& app);
void addGenerateCommand(CLI::App& app);
void addImportCommand(CLI::App& app);
void addInfoCommand(CLI::App& app);
/// What `regolith info FILE [--json]` prints (docs/cli.md), written to `out`: a store's grids,
/// or what an import would make of a raster. Throws regolith::Error and its kinds for a
/// file it cannot describe.
void printInfo(const std::string& file, bool json, std::ostream& out);
void addQueryCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addReportCommand(CLI::App& app);
/// `regolith view` (ViewCommand.cpp): registered only where GLFW is found.
void addViewCommand(CLI::App& app);
/// `regolith render CATALOGUE --look-at lon,lat --distance --elevation --heading` into `png`:
/// one view of a catalogue file's composed surface (the main demo's pole views). Writes the
/// command's one-line report to `report`.
void renderCatalogueView(const std::filesystem::path& catalogue, double lonDeg, double latDeg,
                         double distance, double elevationDeg, double headingDeg,
                         const std::filesystem::path& png, int width, int height,
                         std::ostream& report);

}  // namespace regolith::tools
