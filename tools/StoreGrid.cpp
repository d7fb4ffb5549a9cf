#include "StoreGrid.hpp"

#include <regolith/core/Error.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <vector>

namespace regolith::tools {

void addStoreGridOptions(CLI::App& cmd, std::string& store, std::string& grid, std::size_t& cacheMb,
                         const std::string& verb) {
  cmd.add_option("store", store, "Store file (HDF5)")->required();
  cmd.add_option("--grid", grid, "Grid to " + verb + " (default: the store's only grid)");
  cmd.add_option("--cache-mb", cacheMb, "Patch cache budget in MiB")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20U))
      ->capture_default_str();
}

std::string chooseGrid(const store::Store& s, const std::string& requested,
                       const std::string& command) {
  if (!requested.empty()) return requested;
  std::vector<std::string> names = s.gridNames();
  if (names.size() == 1) return names[0];
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  throw InvalidArgument(command + ": " + s.path().string() + " has " +
                        std::to_string(names.size()) + " grids (" + list +
                        "); choose one with --grid");
}

}  // namespace regolith::tools
