// writer::encodeChunk() and writer::writeBandChunks(): chunks encoded on worker threads and
// written in order.
#include <regolith/core/Executor.hpp>

#include "WriterParts.hpp"

#include <libdeflate.h>
#include <zfp.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <thread>

namespace regolith::store::writer {

// ---- parallel chunk encoding ------------------------------------------------------------------
// Chunks are computed (source reads, 2×2 means) and encoded (HDF5's shuffle then deflate
// filters, applied here with libdeflate) by worker threads, then written in a fixed order with
// H5Dwrite_chunk under the HDF5 lock. The file does not depend on the thread count.

static_assert(std::endian::native == std::endian::little,
              "chunks are written as raw little-endian float32 (H5T_IEEE_F32LE)");

unsigned threadCount(const WriteOptions& o) {
  if (o.threads > 0) return o.threads;
  if (o.executor != nullptr) return o.executor->concurrency() + 1;
  return core::availableCores();
}

/// Runs f(0) … f(n − 1) on up to threadCount(o) threads, the caller's included: on the
/// options' executor, or on a pool made for the call; rethrows the first exception once all
/// have stopped.
void parallelFor(std::size_t n, const WriteOptions& o, const std::function<void(std::size_t)>& f) {
  core::parallelFor(o.executor, n, f, threadCount(o));
}

namespace {

/// A chunk of cr × cc floats as H5Z-ZFP (filter 32013) stores it in reversible mode: one bare
/// ZFP stream, no header (the header is in the filter's stored values). Like the plugin, a
/// chunk with a dimension of 1 is one-dimensional. Lossless for every float, NaN included.
std::vector<unsigned char> zfpEncode(std::vector<float>& full, std::size_t cr, std::size_t cc) {
  // Per thread, as for deflate below. zfp_stream_open allocates nothing but the stream.
  struct Stream {
    zfp_stream* z = zfp_stream_open(nullptr);
    Stream() {
      if (z != nullptr) zfp_stream_set_reversible(z);
    }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
    Stream(Stream&&) = delete;
    Stream& operator=(Stream&&) = delete;
    ~Stream() { zfp_stream_close(z); }
  };
  thread_local Stream stream;
  if (stream.z == nullptr) throw StoreError("store::writeStore(): cannot open a ZFP stream");
  zfp_field* field = cr == 1 || cc == 1 ? zfp_field_1d(full.data(), zfp_type_float, cr * cc)
                                        : zfp_field_2d(full.data(), zfp_type_float, cc, cr);
  if (field == nullptr) throw StoreError("store::writeStore(): cannot describe a ZFP field");
  std::vector<unsigned char> out(zfp_stream_maximum_size(stream.z, field));
  bitstream* bits = stream_open(out.data(), out.size());
  zfp_stream_set_bit_stream(stream.z, bits);
  zfp_stream_rewind(stream.z);
  const std::size_t size = zfp_compress(stream.z, field);
  stream_close(bits);
  zfp_field_free(field);
  if (size == 0) throw StoreError("store::writeStore(): cannot compress a chunk with ZFP");
  out.resize(size);
  return out;
}

}  // namespace

/// One chunk as HDF5 stores it: the block padded to the full chunk shape with `fill`, then
/// ZFP-encoded (Codec::Zfp) or, with deflate, byte-shuffled (H5Z_FILTER_SHUFFLE) and
/// zlib-compressed (H5Z_FILTER_DEFLATE).
std::vector<unsigned char> encodeChunk(const float* block, std::size_t nr, std::size_t nc,
                                       const std::array<hsize_t, 2>& chunk, float fill,
                                       const WriteOptions& o) {
  const std::size_t cr = chunk[0], cc = chunk[1], n = cr * cc;
  const int deflate = o.deflate;
  std::vector<float> full(n, fill);
  for (std::size_t r = 0; r < nr; ++r) {
    std::copy_n(block + r * nc, nc, full.begin() + static_cast<std::ptrdiff_t>(r * cc));
  }
  if (o.codec == Codec::Zfp) return zfpEncode(full, cr, cc);
  std::vector<unsigned char> raw(n * sizeof(float));
  std::memcpy(raw.data(), full.data(), raw.size());
  if (deflate <= 0) return raw;
  std::vector<unsigned char> shuffled(raw.size());
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t b = 0; b < sizeof(float); ++b)
      shuffled[b * n + i] = raw[i * sizeof(float) + b];
  }
  // One compressor per thread and level (libdeflate: zlib-format output, which is what
  // HDF5's deflate filter reads, at several times zlib's speed).
  struct Compressor {
    int level = -1;
    libdeflate_compressor* c = nullptr;
    Compressor() = default;
    Compressor(const Compressor&) = delete;
    Compressor& operator=(const Compressor&) = delete;
    Compressor(Compressor&&) = delete;
    Compressor& operator=(Compressor&&) = delete;
    ~Compressor() { libdeflate_free_compressor(c); }
  };
  thread_local Compressor comp;
  if (comp.level != deflate) {
    libdeflate_free_compressor(comp.c);
    comp.c = libdeflate_alloc_compressor(deflate);
    comp.level = comp.c != nullptr ? deflate : -1;
  }
  if (comp.c == nullptr) throw StoreError("store::writeStore(): cannot allocate a compressor");
  std::vector<unsigned char> out(libdeflate_zlib_compress_bound(comp.c, shuffled.size()));
  const std::size_t size =
      libdeflate_zlib_compress(comp.c, shuffled.data(), shuffled.size(), out.data(), out.size());
  if (size == 0) throw StoreError("store::writeStore(): cannot compress a chunk");
  out.resize(size);
  return out;
}

/// Writes rows [r0, r0 + nr) of a dataset whose chunks are `chunk`, chunk column by chunk
/// column: block(c0, nc, out) fills the nr×nc block at column c0 (on a worker thread), the
/// encoded chunks are then written in order. With groupChunks > 0 the band goes in column
/// tiles of that many chunks, each computed, encoded and written before the next, and
/// beforeGroup(c0, nc) (if set) runs first for the tile's columns [c0, c0 + nc) on the calling
/// thread. The file does not depend on the grouping.
void writeBandChunks(
    const LevelWriter& writer, const std::array<hsize_t, 2>& chunk, std::size_t r0, std::size_t nr,
    std::size_t cols, float fill, const WriteOptions& o,
    const std::function<void(std::size_t, std::size_t, std::vector<float>&)>& block,
    Progress& progress, const std::string& what, const Context& ctx, std::size_t groupChunks,
    const std::function<void(std::size_t, std::size_t)>& beforeGroup) {
  const std::size_t cc = chunk[1];
  const std::size_t n = (cols + cc - 1) / cc;
  const std::size_t group = groupChunks == 0 ? n : std::min(groupChunks, n);
  for (std::size_t g0 = 0; g0 < n; g0 += group) {
    const std::size_t gn = std::min(group, n - g0);
    if (beforeGroup) beforeGroup(g0 * cc, std::min(gn * cc, cols - g0 * cc));
    std::vector<std::vector<unsigned char>> encoded(gn);
    parallelFor(gn, o, [&](std::size_t i) {
      checkCancel(o, ctx);  // before every chunk
      std::vector<float> b;
      const std::size_t c0 = (g0 + i) * cc, nc = std::min(cc, cols - c0);
      block(c0, nc, b);
      encoded[i] = encodeChunk(b.data(), nr, nc, chunk, fill, o);
    });
    for (std::size_t i = 0; i < gn; ++i) {
      const std::size_t c0 = (g0 + i) * cc;
      writer.writeChunk(r0, c0, encoded[i]);
      std::vector<unsigned char>().swap(encoded[i]);
      progress.advance(static_cast<double>(nr * std::min(cc, cols - c0)), what);
    }
  }
}

}  // namespace regolith::store::writer
