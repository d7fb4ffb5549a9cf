#include <regolith/core/Error.hpp>
#include <regolith/store/Prefetcher.hpp>

#include <algorithm>
#include <string>

namespace regolith::store {

bool Prefetcher::ItemOrder::operator()(const Item& a, const Item& b) const noexcept {
  // std::priority_queue pops the greatest: higher priority, then coarser level, then older.
  if (a.priority != b.priority) return a.priority < b.priority;
  if (a.level != b.level) return a.level < b.level;
  return a.sequence > b.sequence;
}

namespace {

std::shared_ptr<core::Executor> poolOf(std::size_t threads) {
  if (threads == 0) throw InvalidArgument("store::Prefetcher(): threads is 0, expected >= 1");
  return std::make_shared<core::ThreadPool>(static_cast<unsigned>(threads));
}

}  // namespace

Prefetcher::Prefetcher(std::shared_ptr<const Pager> pager, std::size_t threads)
    : Prefetcher(std::move(pager), poolOf(threads), threads) {}

Prefetcher::Prefetcher(std::shared_ptr<const Pager> pager, std::shared_ptr<core::Executor> executor,
                       std::size_t maxTasks)
    : pager_(std::move(pager)), executor_(std::move(executor)) {
  if (!pager_) throw InvalidArgument("store::Prefetcher(): pager is null");
  if (!executor_) throw InvalidArgument("store::Prefetcher(): executor is null");
  maxTasks_ = maxTasks != 0 ? maxTasks : std::max(1U, executor_->concurrency());
}

Prefetcher::~Prefetcher() {
  std::unique_lock lock(mutex_);
  stopping_ = true;
  stats_.cancelled += queue_.size();
  queue_ = {};
  pending_.clear();
  done_.notify_all();
  // Loading tasks read this object: wait until every one has returned (a load in progress
  // finishes first).
  done_.wait(lock, [&] { return tasks_ == 0; });
}

void Prefetcher::startTasks(std::unique_lock<std::mutex>& lock) {
  // One task per queued patch, up to maxTasks_; each drains the queue and then returns, so
  // the executor's threads are never held while there is nothing to load.
  const std::size_t start = tasks_ < maxTasks_ ? std::min(maxTasks_ - tasks_, queue_.size()) : 0;
  tasks_ += start;
  lock.unlock();
  for (std::size_t i = 0; i < start; ++i) executor_->submit([this] { work(); });
  lock.lock();
}

Prefetcher::Ticket Prefetcher::request(std::string_view grid,
                                       const std::vector<LevelWindow>& windows, int priority) {
  const GridInfo& info = pager_->grid(grid);  // throws StoreError for unknown grids
  std::vector<Item> items;
  for (const LevelWindow& w : windows) {
    (void)pager_->keyOf(grid, w.level, 0, 0);  // throws StoreError for a missing level
    const std::size_t rows = info.levelRows(w.level), cols = info.levelCols(w.level);
    if (w.rows == 0 || w.cols == 0 || w.row0 >= rows || w.col0 >= cols) continue;
    const std::size_t r1 = std::min(rows, w.row0 + w.rows), c1 = std::min(cols, w.col0 + w.cols);
    for (std::size_t pr = w.row0 / info.patchRows; pr * info.patchRows < r1; ++pr) {
      for (std::size_t pc = w.col0 / info.patchCols; pc * info.patchCols < c1; ++pc) {
        const PatchKey key = pager_->keyOf(grid, w.level, pr * info.patchRows, pc * info.patchCols);
        items.push_back({priority, key.level, 0, 0, key});
      }
    }
  }
  std::unique_lock lock(mutex_);
  const Ticket ticket = nextTicket_++;
  for (Item& it : items) {
    it.ticket = ticket;
    it.sequence = nextSequence_++;
    queue_.push(it);
  }
  if (!items.empty()) pending_[ticket] = items.size();
  stats_.queued += items.size();
  startTasks(lock);
  return ticket;
}

std::vector<LevelWindow> Prefetcher::focusWindows(std::string_view grid, std::size_t row,
                                                  std::size_t col, std::size_t radius,
                                                  std::size_t finestLevel) const {
  const GridInfo& info = pager_->grid(grid);
  std::vector<LevelWindow> out;
  for (std::size_t level = finestLevel; level < info.levels; ++level) {
    const std::size_t r = row >> level, c = col >> level;
    const std::size_t rad =
        std::max<std::size_t>(1, (radius + (std::size_t{1} << level) - 1) >> level);
    const std::size_t r0 = r > rad ? r - rad : 0, c0 = c > rad ? c - rad : 0;
    out.push_back({level, r0, c0, r + rad + 1 - r0, c + rad + 1 - c0});
  }
  return out;
}

void Prefetcher::cancel(Ticket ticket) {
  const std::lock_guard lock(mutex_);
  std::vector<Item> keep;
  std::size_t dropped = 0;
  while (!queue_.empty()) {
    if (queue_.top().ticket == ticket) {
      ++dropped;
    } else {
      keep.push_back(queue_.top());
    }
    queue_.pop();
  }
  for (const Item& it : keep) queue_.push(it);
  stats_.cancelled += dropped;
  if (auto p = pending_.find(ticket); p != pending_.end()) {
    p->second -= dropped;
    if (p->second == 0) pending_.erase(p);
  }
  done_.notify_all();
}

void Prefetcher::wait(Ticket ticket) {
  std::unique_lock lock(mutex_);
  done_.wait(lock, [&] { return stopping_ || !pending_.contains(ticket); });
}

void Prefetcher::waitIdle() {
  std::unique_lock lock(mutex_);
  done_.wait(lock, [&] { return stopping_ || (queue_.empty() && busy_ == 0); });
}

PrefetchStats Prefetcher::stats() const {
  const std::lock_guard lock(mutex_);
  return stats_;
}

std::string Prefetcher::lastError() const {
  const std::lock_guard lock(mutex_);
  return lastError_;
}

void Prefetcher::setOnLoaded(std::function<void(const PatchKey&)> fn) {
  const std::lock_guard lock(mutex_);
  onLoaded_ = std::move(fn);
}

void Prefetcher::work() {
  std::unique_lock lock(mutex_);
  while (!stopping_ && !queue_.empty()) {
    const Item item = queue_.top();
    queue_.pop();
    ++busy_;
    const auto onLoaded = onLoaded_;
    lock.unlock();
    std::string error;
    try {
      (void)pager_->patch(item.key);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (error.empty() && onLoaded) onLoaded(item.key);
    lock.lock();
    --busy_;
    if (error.empty()) {
      ++stats_.loaded;
    } else {
      ++stats_.failed;
      lastError_ = std::move(error);
    }
    if (auto p = pending_.find(item.ticket); p != pending_.end() && --p->second == 0) {
      pending_.erase(p);
    }
    done_.notify_all();
  }
  --tasks_;
  done_.notify_all();
}

}  // namespace regolith::store
