// Store reads of chunks whose chunk index lies (found by tests/fuzz/fuzz_store, issue 17):
// HDF5 1.10 trusts a chunk's recorded size and filter mask, so a 123-byte chunk marked "not
// compressed" made H5Dread copy a whole 128-byte chunk out of it (a heap overflow inside
// HDF5). Store::readWindow() now checks each chunk it reads against the file before HDF5
// decodes it. The corrupt chunks are written here with HDF5's own H5Dwrite_chunk.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::store;

/// A planet grid of 8 × 16 float32 samples in 4 × 8 chunks (128 bytes each), sample (r, c)
/// = 100·r + c; deflate level 6 (shuffle + deflate) or uncompressed.
std::filesystem::path writeGrid(const std::string& name, int deflate) {
  GridInfo g;
  g.name = "g";
  g.kind = GridKind::Planet;
  g.rows = 8;
  g.cols = 16;
  g.x0 = -168.75;
  g.y0 = 78.75;
  g.spacingX = g.spacingY = 22.5;
  WriteOptions o;
  o.patchRows = 4;
  o.patchCols = 8;
  o.levels = 1;
  o.deflate = deflate;
  o.threads = 1;
  const GridSource src{
      g, topo::InMemorySamples::fromFunction(
             8, 16, [](std::size_t r, std::size_t c) { return static_cast<float>(100 * r + c); })};
  const std::filesystem::path path = test::scratchFile("StoreCorruptChunk", name);
  writeStore(path, std::span<const GridSource>(&src, 1), o);
  return path;
}

/// Replaces the stored bytes of level 0's chunk at (0, 0) with `bytes`, under `mask`.
void overwriteChunk(const std::filesystem::path& path, unsigned mask, std::size_t bytes) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t ds = H5Dopen2(file, "/grids/g/level0", H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  const std::array<hsize_t, 2> offset{0, 0};
  const std::vector<std::uint8_t> data(bytes, 0x42);
  EXPECT_GE(H5Dwrite_chunk(ds, H5P_DEFAULT, mask, offset.data(), data.size(), data.data()), 0);
  H5Dclose(ds);
  H5Fclose(file);
}

/// The message of the StoreError that reading chunk (0, 0) raises; "" if none.
std::string readFirstChunkError(const std::filesystem::path& path) {
  const Store s = Store::open(path);
  std::vector<float> out(4 * 8);
  try {
    s.readWindow("g", 0, 0, 0, 4, 8, out);
  } catch (const StoreError& e) {
    return e.what();
  }
  return "";
}

/// The chunk at (0, 8) of level 0 is untouched: it reads back exactly.
void expectSecondChunkIntact(const std::filesystem::path& path) {
  const Store s = Store::open(path);
  std::vector<float> out(4 * 8);
  s.readWindow("g", 0, 0, 8, 4, 8, out);
  for (std::size_t r = 0; r < 4; ++r) {
    for (std::size_t c = 0; c < 8; ++c)
      EXPECT_EQ(out[r * 8 + c], static_cast<float>(100 * r + 8 + c));
  }
}

std::string expected(const std::filesystem::path& path, const std::string& recorded,
                     const std::string& expectation) {
  return "store::readWindow\\(\\): " + path.string() +
         ": cannot read grid 'g' dataset 'level0': the chunk at row 0, col 0 is recorded as " +
         recorded + ", expected " + expectation +
         " bytes within the file's [0-9]+ \\(corrupt chunk index\\)";
}

TEST(StoreCorruptChunk, ReadRefusesAChunkMarkedUncompressedThatIsShorterThanAChunk) {
  const auto path = writeGrid("short_raw.h5", 6);
  overwriteChunk(path, 0x3, 123);  // shuffle and deflate skipped: 123 raw bytes for 128
  const std::string message = readFirstChunkError(path);
  EXPECT_TRUE(std::regex_match(
      message, std::regex(expected(
                   path, "123 bytes at byte [0-9]+ not compressed \\(filter mask 3\\)", "128"))))
      << message;
  expectSecondChunkIntact(path);
}

TEST(StoreCorruptChunk, ReadRefusesACompressedChunkTooLargeForItsChunk) {
  const auto path = writeGrid("large_deflate.h5", 6);
  overwriteChunk(path, 0, 257);  // more than twice the 128 bytes it decodes to
  const std::string message = readFirstChunkError(path);
  EXPECT_TRUE(std::regex_match(
      message, std::regex(expected(path, "257 bytes at byte [0-9]+ compressed", "at most 256"))))
      << message;
  expectSecondChunkIntact(path);
}

TEST(StoreCorruptChunk, ChunksStoredAsTheWriterStoresThemStillRead) {
  for (const int deflate : {0, 6}) {
    const auto path = writeGrid("intact_" + std::to_string(deflate) + ".h5", deflate);
    const std::vector<float> v = test::readLevel0(path, "g");
    for (std::size_t i = 0; i < v.size(); ++i) {
      EXPECT_EQ(v[i], static_cast<float>(100 * (i / 16) + i % 16));
    }
  }
}

}  // namespace
