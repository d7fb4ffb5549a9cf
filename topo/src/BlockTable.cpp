#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/BlockTable.hpp>

#include <linux/membarrier.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <string>

namespace regolith::topo {

BlockTable::BlockTable(std::size_t rows, std::size_t cols, std::size_t blockRows,
                       std::size_t blockCols)
    : rows_(rows), cols_(cols), blockRows_(blockRows), blockCols_(blockCols) {
  const auto sizes = [&] {
    return core::number(rows) + " x " + core::number(cols) + " samples in blocks of " +
           core::number(blockRows) + " x " + core::number(blockCols);
  };
  if (rows == 0 || cols == 0 || blockRows == 0 || blockCols == 0) {
    throw InvalidArgument("topo::BlockTable(): " + sizes() + ", expected every size > 0");
  }
  blocksPerRow_ = cols / blockCols + (cols % blockCols != 0 ? 1 : 0);
  blocksPerCol_ = rows / blockRows + (rows % blockRows != 0 ? 1 : 0);
  pow2_ = std::has_single_bit(blockRows) && std::has_single_bit(blockCols);
  if (pow2_) {
    rowShift_ = static_cast<unsigned>(std::countr_zero(blockRows));
    colShift_ = static_cast<unsigned>(std::countr_zero(blockCols));
  }
  static_assert(kMaxBlocks * sizeof(Entry) <= kMaxReservedBytes);
  std::size_t blocks = 0, bytes = 0;
  if (__builtin_mul_overflow(blocksPerRow_, blocksPerCol_, &blocks) ||
      __builtin_mul_overflow(blocks, sizeof(Entry), &bytes) || bytes > kMaxReservedBytes) {
    throw InvalidArgument(
        "topo::BlockTable(): " + sizes() + " need " +
        core::number(static_cast<double>(blocksPerRow_) * static_cast<double>(blocksPerCol_)) +
        " blocks, expected at most " + core::number(kMaxBlocks) + " (use larger blocks)");
  }
  // Zero pages on demand: see the class comment.
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) {
    const int err = errno;
    throw Error("topo::BlockTable(): " + sizes() + ": could not reserve " + core::number(bytes) +
                " bytes of address space (" + std::strerror(err) + ")");
  }
  entries_ = static_cast<Entry*>(p);
  mappedBytes_ = bytes;
  // The counts: one per page of slots, then one per page of counts (how many of its
  // counts are not zero), each lazily backed like the slots.
  // The system's page size (a power of two; 4 KiB where sysconf fails).
  const long reported = sysconf(_SC_PAGESIZE);
  const std::size_t page =
      reported >= 4096 && std::has_single_bit(static_cast<std::size_t>(reported))
          ? static_cast<std::size_t>(reported)
          : 4096;
  pageShift_ = static_cast<unsigned>(std::countr_zero(page));
  const std::size_t slotPages = (bytes + page - 1) >> pageShift_;
  const std::size_t countsPerPage = page / sizeof(std::uint32_t);
  const std::size_t countPages = (slotPages + countsPerPage - 1) / countsPerPage;
  countBytes_ = (countPages * countsPerPage + countPages) * sizeof(std::uint32_t);
  void* q = mmap(nullptr, countBytes_, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (q == MAP_FAILED) {
    const int err = errno;
    munmap(entries_, mappedBytes_);
    throw Error("topo::BlockTable(): " + sizes() + ": could not reserve " +
                core::number(countBytes_) + " bytes of address space (" + std::strerror(err) + ")");
  }
  pageCounts_ = static_cast<std::uint32_t*>(q);
  countPageCounts_ = pageCounts_ + countPages * countsPerPage;
}

BlockTable::~BlockTable() {
  munmap(pageCounts_, countBytes_);
  munmap(entries_, mappedBytes_);
}

namespace {
// Gives one page back to the kernel (it then reads as zeros). A failure only keeps it.
void releasePage(void* page, unsigned pageShift) noexcept {
  (void)madvise(page, std::size_t{1} << pageShift, MADV_DONTNEED);
}
}  // namespace

void BlockTable::countSlot(std::size_t index, bool published) noexcept {
  const std::size_t countsPerPage = (std::size_t{1} << pageShift_) / sizeof(std::uint32_t);
  const std::size_t first = (index * sizeof(Entry)) >> pageShift_;
  const std::size_t last = (index * sizeof(Entry) + sizeof(Entry) - 1) >> pageShift_;
  for (std::size_t pg = first; pg <= last; ++pg) {
    const std::size_t cp = pg / countsPerPage;
    if (published) {
      if (pageCounts_[pg]++ == 0) ++countPageCounts_[cp];
      continue;
    }
    if (--pageCounts_[pg] != 0) continue;
    // Every slot overlapping the page is empty: give it back. Readers racing with this
    // read either the empty slots or the zero page, both "not published"; every hint
    // pointer in it is null already.
    releasePage(reinterpret_cast<char*>(entries_) + (pg << pageShift_), pageShift_);  // NOLINT
    if (--countPageCounts_[cp] == 0) releasePage(pageCounts_ + cp * countsPerPage, pageShift_);
  }
}

void BlockTable::publish(std::size_t blockRow, std::size_t blockCol,
                         const PublishedBlock* block) noexcept {
  const std::size_t i = blockRow * blocksPerRow_ + blockCol;
  Entry& e = entries_[i];
  // Counted before the slot's page is written (the counts are the writers' alone).
  if (Slot(e.block).load(std::memory_order_relaxed) == nullptr) countSlot(i, true);
  std::atomic_ref(e.hintStride).store(block->stride, std::memory_order_relaxed);
  std::atomic_ref(e.hintData).store(block->data, std::memory_order_relaxed);
  Slot(e.block).store(block, std::memory_order_release);
}

void BlockTable::retract(std::size_t blockRow, std::size_t blockCol) noexcept {
  const std::size_t i = blockRow * blocksPerRow_ + blockCol;
  Entry& e = entries_[i];
  const bool wasPublished = Slot(e.block).load(std::memory_order_relaxed) != nullptr;
  std::atomic_ref(e.hintData).store(nullptr, std::memory_order_relaxed);
  Slot(e.block).store(nullptr, std::memory_order_seq_cst);
  if (wasPublished) countSlot(i, false);
}

namespace hazard {
namespace {

std::atomic<Record*> gRecords{nullptr};  // NOLINT: the registry; records are never freed

[[maybe_unused]] long membarrier(int cmd) { return syscall(__NR_membarrier, cmd, 0U, 0); }

// Registers this process for expedited membarriers once. Failing that (an old kernel, a
// seccomp filter), queries do not use the block tables (tlFastRecord stays null).
void initOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
#if !defined(__SANITIZE_THREAD__)
    const long cmds = membarrier(MEMBARRIER_CMD_QUERY);
    if (cmds > 0 && (cmds & MEMBARRIER_CMD_PRIVATE_EXPEDITED) != 0 &&
        membarrier(MEMBARRIER_CMD_REGISTER_PRIVATE_EXPEDITED) == 0) {
      gAsymmetric.store(true, std::memory_order_seq_cst);
    }
#endif
  });
}

// Gives the thread's record back when the thread ends.
struct Releaser {
  Record* rec = nullptr;
  Releaser() = default;
  Releaser(const Releaser&) = delete;
  Releaser& operator=(const Releaser&) = delete;
  ~Releaser() {
    if (rec != nullptr) {
      rec->ptr.store(nullptr, std::memory_order_release);
      rec->inUse.store(false, std::memory_order_release);
      tlRecord = tlFastRecord = nullptr;  // a later query in this thread registers anew
    }
  }
};
thread_local Releaser tlReleaser;  // NOLINT

}  // namespace

Record& acquire() {
  if (tlRecord != nullptr) return *tlRecord;
  initOnce();
  Record* rec = nullptr;
  // Reuse a record of a thread that has ended, else add one.
  for (Record* r = gRecords.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    bool expected = false;
    if (!r->inUse.load(std::memory_order_relaxed) &&
        r->inUse.compare_exchange_strong(expected, true, std::memory_order_acq_rel)) {
      rec = r;
      break;
    }
  }
  if (rec == nullptr) {
    rec = new Record;  // NOLINT(cppcoreguidelines-owning-memory): lives for the process
    rec->inUse.store(true, std::memory_order_relaxed);
    Record* head = gRecords.load(std::memory_order_relaxed);
    do {
      rec->next = head;
    } while (!gRecords.compare_exchange_weak(head, rec, std::memory_order_release,
                                             std::memory_order_relaxed));
  }
  tlReleaser.rec = rec;
  tlRecord = rec;
#if defined(__SANITIZE_THREAD__)
  tlFastRecord = rec;
#else
  if (gAsymmetric.load(std::memory_order_relaxed)) tlFastRecord = rec;
#endif
  return *rec;
}

bool barrier() noexcept {
#if defined(__SANITIZE_THREAD__)
  // Readers store their hazards sequentially consistently and retract() is a seq_cst
  // store, so the seq_cst loads of isProtected() need no fence (TSan cannot check fences).
  return true;
#else
  if (gAsymmetric.load(std::memory_order_relaxed)) {
    // Readers did not fence: without the process-wide barrier nothing may be freed now.
    return membarrier(MEMBARRIER_CMD_PRIVATE_EXPEDITED) == 0;
  }
  std::atomic_thread_fence(std::memory_order_seq_cst);
  return true;
#endif
}

bool isProtected(const void* p) noexcept {
  for (Record* r = gRecords.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    if (r->ptr.load(std::memory_order_seq_cst) == p) return true;
  }
  return false;
}

void forget(const void* p) noexcept {
  for (Record* r = gRecords.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    const void* expected = p;
    r->ptr.compare_exchange_strong(expected, nullptr, std::memory_order_acq_rel);
  }
}

}  // namespace hazard
}  // namespace regolith::topo
