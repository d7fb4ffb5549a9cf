#pragma once
// Sample sources that steer a query's path, for tests that compare the fast paths of
// TopoDem and TopoPlanet with the generic kernel on the same samples.
#include <regolith/store/BlockSource.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace regolith::test {

// Only sample(): every query takes the generic kernel.
class SampleOnlySource final : public topo::SampleSource {
 public:
  SampleOnlySource(std::size_t rows, std::size_t cols, std::vector<float> data)
      : rows_(rows), cols_(cols), data_(std::move(data)) {}
  std::size_t rows() const noexcept override { return rows_; }
  std::size_t cols() const noexcept override { return cols_; }
  float sample(std::size_t r, std::size_t c) const override { return data_.at(r * cols_ + c); }

 private:
  std::size_t rows_, cols_;
  std::vector<float> data_;
};

// Blocks of 7 × 5 samples, as a pager hands out patches (a store::BlockSource without a
// block table): cells straddle block edges on rows 6, 13, … and columns 4, 9, …. Counts its
// calls (sample(), block()).
class BlockSource final : public store::BlockSource {
 public:
  BlockSource(std::size_t rows, std::size_t cols, std::vector<float> data)
      : rows_(rows), cols_(cols), data_(std::make_shared<std::vector<float>>(std::move(data))) {}
  std::size_t rows() const noexcept override { return rows_; }
  std::size_t cols() const noexcept override { return cols_; }
  float sample(std::size_t r, std::size_t c) const override {
    sampleCalls.fetch_add(1, std::memory_order_relaxed);
    return (*data_)[r * cols_ + c];
  }
  store::SampleBlock block(std::size_t r, std::size_t c) const override {
    blockCalls.fetch_add(1, std::memory_order_relaxed);
    const std::size_t r0 = r / 7 * 7, c0 = c / 5 * 5;
    return {data_->data() + r0 * cols_ + c0,      r0,    c0,   std::min<std::size_t>(7, rows_ - r0),
            std::min<std::size_t>(5, cols_ - c0), cols_, data_};
  }

  mutable std::atomic<std::size_t> sampleCalls{0}, blockCalls{0};

 private:
  std::size_t rows_, cols_;
  std::shared_ptr<std::vector<float>> data_;
};

}  // namespace regolith::test
