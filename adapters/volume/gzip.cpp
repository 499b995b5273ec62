// gzip through zlib: pigz's way of compressing pieces in parallel into one stream, and an
// inflater that never writes beyond the size the caller expects.
#include "occseg/gzip.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <new>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"

namespace occseg {

void report_progress(const IoProgress& progress, double fraction) {
  if (progress && !progress(std::clamp(fraction, 0.0, 1.0))) throw Error(Status::cancelled, "cancelled");
}

namespace {

struct Piece {
  std::vector<unsigned char> out;
  std::size_t used = 0;
  uLong crc = 0;
};

// Raw deflate of one piece; the last one ends the stream (Z_FINISH), the others end with a full
// flush at a byte boundary and no history, so the next piece can start a fresh deflater.
void deflate_piece(const unsigned char* in, std::size_t n, bool last, int level, Piece& p) {
  z_stream s{};
  const int rc = deflateInit2(&s, level, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY);
  if (rc == Z_MEM_ERROR) throw std::bad_alloc();
  if (rc != Z_OK) throw Error(Status::internal, "zlib deflateInit2 failed");
  const std::size_t bound = deflateBound(&s, static_cast<uLong>(n)) + 64;  // + the flush marker
  if (p.out.size() < bound) p.out.resize(bound);
  s.next_in = const_cast<Bytef*>(in);
  s.avail_in = static_cast<uInt>(n);
  s.next_out = p.out.data();
  s.avail_out = static_cast<uInt>(p.out.size());
  const int r = deflate(&s, last ? Z_FINISH : Z_FULL_FLUSH);
  const bool ok = last ? r == Z_STREAM_END : (r == Z_OK && s.avail_in == 0 && s.avail_out > 0);
  p.used = p.out.size() - s.avail_out;
  deflateEnd(&s);
  if (!ok) throw Error(Status::internal, "zlib deflate failed on a piece of " + std::to_string(n) + " bytes");
  p.crc = crc32(0L, in, static_cast<uInt>(n));
}

void put_le32(std::ostream& out, std::uint32_t v) {
  const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                              static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 24)};
  out.write(reinterpret_cast<const char*>(b), 4);
}

}  // namespace

void write_gzip(std::ostream& out, const void* bytes, std::size_t size, int level, int threads,
                const IoProgress& progress) {
  const auto* in = static_cast<const unsigned char*>(bytes);
  // The member header: no name, no time stamp (the file depends on its content only), OS Unix.
  static const unsigned char header[10] = {0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3};
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  const std::size_t pieces = std::max<std::size_t>(1, (size + kGzipPiece - 1) / kGzipPiece);
  const std::size_t batch = 2 * static_cast<std::size_t>(resolve_threads(threads));
  std::vector<Piece> work(std::min(batch, pieces));
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t first = 0; first < pieces; first += work.size()) {
    const std::size_t count = std::min(work.size(), pieces - first);
    parallel_for_dynamic(count, threads, [&](std::size_t a, std::size_t b) {
      for (std::size_t k = a; k < b; ++k) {
        const std::size_t i = first + k, at = i * kGzipPiece;
        deflate_piece(in + std::min(at, size), std::min(kGzipPiece, size - std::min(at, size)), i + 1 == pieces,
                      level, work[k]);
      }
    });
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t i = first + k, n = std::min(kGzipPiece, size - std::min(i * kGzipPiece, size));
      out.write(reinterpret_cast<const char*>(work[k].out.data()), static_cast<std::streamsize>(work[k].used));
      crc = crc32_combine(crc, work[k].crc, static_cast<z_off_t>(n));
    }
    if (!out) return;  // the caller reports the stream's error
    report_progress(progress, double(first + count) / double(pieces));
  }
  put_le32(out, static_cast<std::uint32_t>(crc));
  put_le32(out, static_cast<std::uint32_t>(size & 0xffffffffu));
}

std::string gunzip_exact(const void* data, std::size_t data_size, void* out_bytes, std::size_t size,
                         const IoProgress& progress) {
  const auto* in = static_cast<const unsigned char*>(data);
  auto* out = static_cast<unsigned char*>(out_bytes);
  z_stream s{};
  // 15 + 32: gzip or zlib, told apart by the header.
  const int rc = inflateInit2(&s, 15 + 32);
  if (rc == Z_MEM_ERROR) throw std::bad_alloc();
  if (rc != Z_OK) throw Error(Status::internal, "zlib inflateInit2 failed");
  struct End {
    z_stream* s;
    ~End() { inflateEnd(s); }
  } end{&s};
  constexpr std::size_t kStep = std::size_t(1) << 30;  // zlib counts in 32-bit uInt
  constexpr std::size_t kReport = std::size_t(1) << 24;
  std::size_t in_pos = 0, out_pos = 0, next_report = kReport;
  auto n = [](std::size_t a) { return std::to_string(a); };
  auto promised = [&] { return " of the " + n(size) + " bytes the header promises"; };
  unsigned char spare;  // where a byte beyond `size` would go: decompressing it is an error
  for (;;) {
    const bool full = out_pos == size;
    s.next_in = const_cast<Bytef*>(in + in_pos);
    s.avail_in = static_cast<uInt>(std::min(data_size - in_pos, kStep));
    s.next_out = full ? &spare : out + out_pos;
    s.avail_out = full ? 1u : static_cast<uInt>(std::min(size - out_pos, kStep));
    const uInt in_before = s.avail_in, out_before = s.avail_out;
    const int r = inflate(&s, Z_NO_FLUSH);
    in_pos += in_before - s.avail_in;
    if (full && s.avail_out == 0) return "the gzip data decompresses to more than the " + n(size) + " bytes the header promises";
    if (!full) out_pos += out_before - s.avail_out;
    if (r == Z_STREAM_END) {
      // Another member may follow (gunzip reads concatenated members); other bytes after the
      // stream are ignored, as teem ignores what follows the data it needs.
      const bool member = data_size - in_pos >= 2 && in[in_pos] == 0x1f && in[in_pos + 1] == 0x8b;
      if (member) {
        inflateReset(&s);
        continue;
      }
      if (out_pos < size) return "the gzip data ends after " + n(out_pos) + promised();
      return "";
    }
    if (r == Z_MEM_ERROR) throw std::bad_alloc();
    if (r == Z_DATA_ERROR || r == Z_NEED_DICT || r == Z_STREAM_ERROR)
      return "the gzip data is corrupt (zlib: " + std::string(s.msg ? s.msg : "needs a dictionary") + ") after " +
             n(in_pos) + " of its " + n(data_size) + " bytes";
    if (in_pos == data_size && (r == Z_BUF_ERROR || s.avail_in == 0) && (s.avail_out > 0 || full))
      return "the gzip data is truncated after its " + n(data_size) + " bytes (" + n(out_pos) + promised() +
             " were decompressed)";
    if (out_pos >= next_report) {
      report_progress(progress, double(out_pos) / double(size));
      next_report = out_pos + kReport;
    }
  }
}

}  // namespace occseg
