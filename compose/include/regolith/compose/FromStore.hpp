#pragma once
/// \file
/// Datasets from stores, and catalogue files: a JSON list of store grids with their roles,
/// priorities, feathers and masks (docs/composition.md "Catalogue files").

#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/store/Pager.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace regolith::compose {

/// A dataset of one grid of a store, paged through `pager` (its levels as the pager's
/// pyramid, its placement as the store records it, its height range from the store's
/// statistics when recorded). The options' name defaults to the grid's. Throws StoreError
/// for an unknown grid and InvalidArgument for bad options (Dataset's checks). The pyramid's
/// hints and loads run on `loader` if given (store::Pager::pyramid()).
[[nodiscard]] std::shared_ptr<const Dataset> datasetFromStore(
    const store::Pager& pager, std::string_view grid, DatasetOptions options = {},
    std::shared_ptr<core::Executor> loader = nullptr);

/// A catalogue file, read: its body (from its first dataset), its rules, and its datasets
/// in file order, every store paged through one patch cache.
struct CatalogueFile {
  std::shared_ptr<Catalogue> catalogue;
  Rules rules;
  std::vector<DatasetId> ids;  ///< in file order
  std::vector<std::shared_ptr<const store::Pager>> pagers;
};

/// Reads a catalogue file (JSON):
/// ```
/// { "policy": "weighted" | "finest", "resolution_power": 2, "tier_ratio": 4,
///   "datasets": [ { "store": "mola.h5", "grid": "mola", "role": "height",
///                   "priority": 0, "feather_m": 20000, "height_offset_m": 0,
///                   "mask_grid": "mola_mask", "feather_nodata_samples": 8 } ] }
/// ```
/// Relative store paths are relative to the file's folder. `mask_grid` names a grid of the
/// same store (same size as the dataset's level 0, values in [0, 1]);
/// `feather_nodata_samples` builds a mask from the dataset's nodata border in memory
/// (featherMask(), grids up to 2^28 samples). Every dataset must be on one body. Unknown keys
/// are refused (a misspelt key would silently change the surface). Throws InvalidArgument
/// naming the file, the dataset's index and the key for bad content, IoError if the file
/// cannot be read, StoreError for a bad store. Every dataset's pyramid hints and loads on
/// `loader` if given (datasetFromStore()).
[[nodiscard]] CatalogueFile readCatalogueFile(
    const std::filesystem::path& path, std::size_t cacheBytes = std::size_t{256} << 20,
    const std::shared_ptr<core::Executor>& loader = nullptr);

}  // namespace regolith::compose
