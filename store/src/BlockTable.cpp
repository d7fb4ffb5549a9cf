// The block tables and hazard domains of store/BlockTable.hpp: the tables' lazily backed
// memory (mmap, madvise) and the reclaimer's process-wide barrier (membarrier(2)).
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/BlockTable.hpp>

#include "ThreadQueries.hpp"

#include <linux/membarrier.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

namespace regolith::store {

namespace {

struct EntryLayout {  // the layout of BlockIndex::Entry, for sizes before it exists
  const void* block;
  const float* hintData;
  std::size_t hintStride;
};

std::string describeSizes(std::size_t rows, std::size_t cols, std::size_t blockRows,
                          std::size_t blockCols) {
  return core::number(rows) + " x " + core::number(cols) + " samples in blocks of " +
         core::number(blockRows) + " x " + core::number(blockCols);
}

// The table's sizes, checked, and the bytes of its mapping.
BlockIndex::Geometry checkedGeometry(std::size_t rows, std::size_t cols, std::size_t blockRows,
                                     std::size_t blockCols) {
  if (rows == 0 || cols == 0 || blockRows == 0 || blockCols == 0) {
    throw InvalidArgument(
        "store::BlockTable(): " + describeSizes(rows, cols, blockRows, blockCols) +
        ", expected every size > 0");
  }
  const std::size_t blocksPerRow = cols / blockCols + (cols % blockCols != 0 ? 1 : 0);
  const std::size_t blocksPerCol = rows / blockRows + (rows % blockRows != 0 ? 1 : 0);
  static_assert(BlockTable::kMaxBlocks * sizeof(EntryLayout) <= BlockTable::kMaxReservedBytes);
  std::size_t blocks = 0, bytes = 0;
  if (__builtin_mul_overflow(blocksPerRow, blocksPerCol, &blocks) ||
      __builtin_mul_overflow(blocks, sizeof(EntryLayout), &bytes) ||
      bytes > BlockTable::kMaxReservedBytes) {
    throw InvalidArgument(
        "store::BlockTable(): " + describeSizes(rows, cols, blockRows, blockCols) + " need " +
        core::number(static_cast<double>(blocksPerRow) * static_cast<double>(blocksPerCol)) +
        " blocks, expected at most " + core::number(BlockTable::kMaxBlocks) +
        " (use larger blocks)");
  }
  return {rows, cols, blockRows, blockCols};
}

}  // namespace

BlockTable::BlockTable(std::size_t rows, std::size_t cols, std::size_t blockRows,
                       std::size_t blockCols, std::shared_ptr<HazardDomain> domain)
    : BlockTable(checkedGeometry(rows, cols, blockRows, blockCols),
                 domain ? std::move(domain) : std::make_shared<HazardDomain>()) {}

BlockTable::BlockTable(const Geometry& g, std::shared_ptr<HazardDomain> domain)
    : BlockIndex(g, domain->id(), domain->clock()), domain_(std::move(domain)) {
  static_assert(sizeof(EntryLayout) == sizeof(Entry));
  const auto sizes = [&] { return describeSizes(g.rows, g.cols, g.blockRows, g.blockCols); };
  const std::size_t bytes = blocksPerRow() * blocksPerCol() * sizeof(Entry);  // checked above
  // Zero pages on demand: see the class comment.
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) {
    const int err = errno;
    throw Error("store::BlockTable(): " + sizes() + ": could not reserve " + core::number(bytes) +
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
    throw Error("store::BlockTable(): " + sizes() + ": could not reserve " +
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
  const std::size_t i = blockRow * blocksPerRow() + blockCol;
  Entry& e = entries_[i];
  // Counted before the slot's page is written (the counts are the writers' alone).
  if (Slot(e.block).load(std::memory_order_relaxed) == nullptr) countSlot(i, true);
  std::atomic_ref(e.hintStride).store(block->stride, std::memory_order_relaxed);
  std::atomic_ref(e.hintData).store(block->data, std::memory_order_relaxed);
  Slot(e.block).store(block, std::memory_order_release);
}

void BlockTable::retract(std::size_t blockRow, std::size_t blockCol) noexcept {
  const std::size_t i = blockRow * blocksPerRow() + blockCol;
  Entry& e = entries_[i];
  const bool wasPublished = Slot(e.block).load(std::memory_order_relaxed) != nullptr;
  std::atomic_ref(e.hintData).store(nullptr, std::memory_order_relaxed);
  Slot(e.block).store(nullptr, std::memory_order_seq_cst);
  if (wasPublished) countSlot(i, false);
}

namespace {

std::atomic<std::uint64_t> gNextDomain{1};  // NOLINT: ids only; no state is shared through it
std::atomic<bool> gAsymmetric{false};       // NOLINT: membarrier(2) registered (once)

long membarrier(int cmd) { return syscall(__NR_membarrier, cmd, 0U, 0); }

// Registers this process for expedited membarriers once: the registration is the kernel's,
// per process. Failing that (an old kernel, a seccomp filter), queries do not use the block
// tables (lockFreeRecord() gives null).
void initOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    const long cmds = membarrier(MEMBARRIER_CMD_QUERY);
    if (cmds > 0 && (cmds & MEMBARRIER_CMD_PRIVATE_EXPEDITED) != 0 &&
        membarrier(MEMBARRIER_CMD_REGISTER_PRIVATE_EXPEDITED) == 0) {
      gAsymmetric.store(true, std::memory_order_seq_cst);
    }
  });
}

// The records this thread holds, one per domain it has read, given back when it ends.
struct ThreadRecords {
  struct Held {
    std::uint64_t domain;
    std::weak_ptr<HazardDomain> owner;
    HazardDomain::Record* rec;
  };
  std::vector<Held> held;
  ThreadRecords() = default;
  ThreadRecords(const ThreadRecords&) = delete;
  ThreadRecords& operator=(const ThreadRecords&) = delete;
  ~ThreadRecords() {
    for (const Held& h : held) {
      if (const auto d = h.owner.lock()) {
        h.rec->ptr.store(nullptr, std::memory_order_release);
        h.rec->inUse.store(false, std::memory_order_release);
      }
    }
    detail::forgetThreadHazard();  // a later query in this thread joins anew
  }
};
thread_local ThreadRecords tlRecords;  // NOLINT

}  // namespace

HazardDomain::HazardDomain() : id_(gNextDomain.fetch_add(1, std::memory_order_relaxed)) {
  initOnce();
}

HazardDomain::~HazardDomain() {
  // No table of this domain is alive (each holds the domain), so no query reads a record.
  for (Record* r = records_.load(std::memory_order_acquire); r != nullptr;) {
    Record* next = r->next;
    delete r;  // NOLINT(cppcoreguidelines-owning-memory): the registry owns its records
    r = next;
  }
}

HazardRecord& HazardDomain::threadRecord() {
  std::vector<ThreadRecords::Held>& held = tlRecords.held;
  for (const ThreadRecords::Held& h : held) {
    if (h.domain == id_) return *h.rec;
  }
  // Forget the records of domains that are gone before adding one.
  std::erase_if(held, [](const ThreadRecords::Held& h) { return h.owner.expired(); });
  held.reserve(held.size() + 1);  // the push_back below cannot throw after a record is taken
  Record* rec = nullptr;
  // Reuse a record of a thread that has ended, else add one.
  for (Record* r = records_.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    bool expected = false;
    if (!r->inUse.load(std::memory_order_relaxed) &&
        r->inUse.compare_exchange_strong(expected, true, std::memory_order_acq_rel)) {
      rec = r;
      break;
    }
  }
  if (rec == nullptr) {
    rec = new Record;  // NOLINT(cppcoreguidelines-owning-memory): freed with the domain
    rec->inUse.store(true, std::memory_order_relaxed);
    Record* head = records_.load(std::memory_order_relaxed);
    do {
      rec->next = head;
    } while (!records_.compare_exchange_weak(head, rec, std::memory_order_release,
                                             std::memory_order_relaxed));
  }
  held.push_back({id_, weak_from_this(), rec});
  return *rec;
}

HazardRecord* HazardDomain::lockFreeRecord() {
  if (!lockFree()) return nullptr;
  // The thread now reads through this domain: its hazards elsewhere protect nothing it reads
  // (its queries' thread block was given up when it switched, detail::hazardFor(),
  // BlockSource.cpp).
  for (const ThreadRecords::Held& h : tlRecords.held) {
    if (h.domain == id_) continue;
    if (const auto d = h.owner.lock()) h.rec->ptr.store(nullptr, std::memory_order_release);
  }
  return &threadRecord();
}

bool HazardDomain::lockFree() noexcept { return gAsymmetric.load(std::memory_order_relaxed); }

bool HazardDomain::barrier() noexcept {
  if (gAsymmetric.load(std::memory_order_relaxed)) {
    // Readers did not fence: without the process-wide barrier nothing may be freed now.
    return membarrier(MEMBARRIER_CMD_PRIVATE_EXPEDITED) == 0;
  }
  // No membarrier: no query uses the tables (lockFreeRecord() gives null), so no reader
  // announces a hazard that the barrier would have to order. (A fence on this side alone
  // would not order a reader's announcement before its re-read of the slot anyway.)
  return true;
}

bool HazardDomain::isProtected(const void* p) const noexcept {
  for (Record* r = records_.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    if (r->ptr.load(std::memory_order_seq_cst) == p) return true;
  }
  return false;
}

void HazardDomain::forget(const void* p) noexcept {
  for (Record* r = records_.load(std::memory_order_acquire); r != nullptr; r = r->next) {
    const void* expected = p;
    r->ptr.compare_exchange_strong(expected, nullptr, std::memory_order_acq_rel);
  }
}

}  // namespace regolith::store
