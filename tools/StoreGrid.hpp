#pragma once
// Helpers the subcommands share to pick a store's grid (the renderer's pyramid of a grid is
// store::Pager::pyramid(), drawn by clod::HeightPyramid).
#include <regolith/store/Store.hpp>

#include <cstddef>
#include <string>

namespace CLI {
class App;
}  // namespace CLI

namespace regolith::tools {

/// The options every subcommand that reads one grid of a store shares: the store file
/// (positional), --grid (default: the only grid) and --cache-mb (the patch cache budget).
/// `verb` says what the command does with the grid ("query", "render").
void addStoreGridOptions(CLI::App& cmd, std::string& store, std::string& grid, std::size_t& cacheMb,
                         const std::string& verb);

/// `requested` if not empty (Store::grid() names the grids if it is missing), else the
/// store's only grid; throws InvalidArgument("<command>: <file> has N grids (a, b); choose
/// one with --grid") if there are several.
std::string chooseGrid(const store::Store& s, const std::string& requested,
                       const std::string& command);

}  // namespace regolith::tools
