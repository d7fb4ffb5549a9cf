// The writer's memory plan (WriteOptions::memoryBudgetBytes, docs/import.md "Memory"):
// writer::planMemory(), and store::writerMemoryPlan() and writerMemoryMinimum().
#include "WriterParts.hpp"

#include <algorithm>

namespace regolith::store::writer {

// Estimates of the buffers the writer itself holds, in units of one chunk C of floats:
// - each thread: a block (C), its 4 fine samples (4C), encodeChunk's padded, raw, shuffled and
//   compressed copies (4C, the compressor's bound rounded up): 10C;
// - whole-width bands: per level a held band, the pair it joins (twice), and the band being
//   made (4 bands of that level), and level 0's encoded chunks (5/4 of a band);
// - column tiles of T chunks: the fine tile read back (4TC) and its encoded chunks (5/4 TC).

namespace {

constexpr std::size_t kScratchChunksPerThread = 10;

std::size_t encodedBound(std::size_t bytes) { return bytes + bytes / 4; }

}  // namespace

std::size_t levelCount(const GridInfo& info, const WriteOptions& o) {
  if (o.levels != 0) return std::min(o.levels, format::maxLevels(info.rows, info.cols));
  std::size_t levels = 1;
  while (info.levelRows(levels - 1) > o.patchRows || info.levelCols(levels - 1) > o.patchCols) {
    ++levels;
  }
  return levels;
}

WriterMemoryPlan planMemory(const GridInfo& info, std::size_t levels, const WriteOptions& o) {
  const std::size_t chunk = o.patchRows * o.patchCols * sizeof(float);
  const std::size_t perThread = kScratchChunksPerThread * chunk;
  const std::size_t perTileChunk = 4 * chunk + encodedBound(chunk);
  WriterMemoryPlan plan;
  plan.threads = threadCount(o);
  plan.minimumBytes = perTileChunk + perThread;  // one chunk column, one thread
  const auto band = [&](std::size_t k) {
    return std::min(o.patchRows, info.levelRows(k)) * info.levelCols(k) * sizeof(float);
  };
  plan.untiledBytes = encodedBound(band(0)) + plan.threads * perThread;
  for (std::size_t k = 0; k < levels; ++k) plan.untiledBytes += 4 * band(k);
  std::size_t budget = o.memoryBudgetBytes;
  if (budget == kDefaultMemoryBudget) budget = std::max(budget, plan.minimumBytes);
  if (budget == 0 || plan.untiledBytes <= budget) {
    plan.plannedBytes = plan.untiledBytes;
    return plan;
  }
  // Column tiles: every thread the budget allows beside one tile chunk, then the widest tile.
  const std::size_t room = budget > perTileChunk ? budget - perTileChunk : 0;
  plan.threads = std::clamp<std::size_t>(room / perThread, 1, plan.threads);
  const std::size_t chunkCols = (info.cols + o.patchCols - 1) / o.patchCols;
  const std::size_t scratch = plan.threads * perThread;
  const std::size_t fits = budget > scratch ? (budget - scratch) / perTileChunk : 0;
  plan.tileChunks = std::clamp<std::size_t>(fits, 1, chunkCols);
  plan.plannedBytes = plan.tileChunks * perTileChunk + scratch;
  return plan;
}

}  // namespace regolith::store::writer

namespace regolith::store {

WriterMemoryPlan writerMemoryPlan(std::size_t rows, std::size_t cols, const WriteOptions& options) {
  GridInfo info;
  info.rows = rows;
  info.cols = cols;
  return writer::planMemory(info, writer::levelCount(info, options), options);
}

std::size_t writerMemoryMinimum(const WriteOptions& options) {
  return writerMemoryPlan(1, 1, options).minimumBytes;
}

}  // namespace regolith::store
