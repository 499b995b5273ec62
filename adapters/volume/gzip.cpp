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

// --- runs of whole words, coded by hand with deflate's fixed Huffman codes (RFC 1951, 3.2.6) ---

// Bits, least significant first, as deflate packs them.
class BitSink {
 public:
  explicit BitSink(std::vector<unsigned char>& out) : out_(out) {}
  void put(std::uint32_t bits, int n) {  // n <= 32
    acc_ |= std::uint64_t(bits) << fill_;
    fill_ += n;
    while (fill_ >= 8) {
      out_.push_back(static_cast<unsigned char>(acc_));
      acc_ >>= 8;
      fill_ -= 8;
    }
  }
  // A Huffman code of n bits, which deflate stores most significant bit first.
  void code(std::uint32_t c, int n) { put(reversed(c, n), n); }
  static std::uint32_t reversed(std::uint32_t c, int n) {
    std::uint32_t r = 0;
    for (int k = 0; k < n; ++k) r |= ((c >> k) & 1u) << (n - 1 - k);
    return r;
  }
  void align() {
    if (fill_ > 0) put(0, 8 - fill_);
  }

 private:
  std::vector<unsigned char>& out_;
  std::uint64_t acc_ = 0;
  int fill_ = 0;
};

// The fixed literal/length codes, bit-reversed as they are written, and their lengths.
struct FixedCodes {
  std::uint16_t bits[288];
  std::uint8_t length[288];
  FixedCodes() {
    for (unsigned v = 0; v < 288; ++v) {
      const unsigned c = v < 144 ? 0x30 + v : v < 256 ? 0x190 + (v - 144) : v < 280 ? v - 256 : 0xC0 + (v - 280);
      const int n = v < 144 ? 8 : v < 256 ? 9 : v < 280 ? 7 : 8;
      bits[v] = static_cast<std::uint16_t>(BitSink::reversed(c, n));
      length[v] = static_cast<std::uint8_t>(n);
    }
  }
};
const FixedCodes kFixed;

void fixed_literal(BitSink& b, unsigned v) { b.put(kFixed.bits[v], kFixed.length[v]); }  // 0..287

// A match of `len` (3..258) bytes `dist` (1..32768) bytes back.
void fixed_match(BitSink& b, unsigned len, unsigned dist) {
  static const unsigned short kLenBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                              31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
  static const unsigned char kLenExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
  static const unsigned short kDistBase[30] = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
                                               193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
  static const unsigned char kDistExtra[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
  unsigned l = 28;
  while (kLenBase[l] > len) --l;
  fixed_literal(b, 257 + l);
  if (kLenExtra[l]) b.put(len - kLenBase[l], kLenExtra[l]);
  unsigned d = 29;
  while (kDistBase[d] > dist) --d;
  b.code(d, 5);
  if (kDistExtra[d]) b.put(dist - kDistBase[d], kDistExtra[d]);
}

// `bytes` bytes repeating those `dist` bytes back, as matches of at most 258 bytes (none shorter
// than 3: a remainder of 1 or 2 is taken from the match before it).
void fixed_repeat(BitSink& b, std::size_t bytes, unsigned dist) {
  while (bytes > 0) {
    std::size_t m = std::min<std::size_t>(bytes, 258);
    if (bytes > 258 && bytes - 258 < 3) m = bytes - 3;
    fixed_match(b, static_cast<unsigned>(m), dist);
    bytes -= m;
  }
}

// Piece [begin, end) of `in` (offsets in bytes, multiples of runs.word) as one fixed-Huffman
// block: at each word the longest run of words equal to the word one back, one row back or one
// slice back (those within deflate's 32 KiB window and after the start of the data), else the
// word as literals. A piece that is not the last ends with an empty stored block (zlib's full
// flush), so the pieces concatenate at byte boundaries. Returns false when the piece came out
// larger than `limit` bytes (then `p` is not valid).
bool run_piece(const unsigned char* in, std::size_t begin, std::size_t end, bool last, const GzipRuns& runs,
               std::size_t limit, Piece& p) {
  p.out.clear();
  BitSink b(p.out);
  b.put(last ? 1 : 0, 1);
  b.put(1, 2);  // fixed Huffman codes
  const std::size_t w = runs.word;
  std::size_t dists[3];
  int nd = 0;
  for (const std::size_t d : {std::size_t(1), runs.row, runs.slice})
    if (d > 0 && d * w <= 32768 && std::find(dists, dists + nd, d * w) == dists + nd) dists[nd++] = d * w;
  std::size_t at = begin;
  while (at < end) {
    std::size_t best = 0, best_d = 0;
    for (int k = 0; k < nd; ++k) {
      const std::size_t d = dists[k];
      if (d > at) continue;
      const unsigned char* a = in + at;
      const unsigned char* r = a - d;
      std::size_t n = 0;
      const std::size_t most = end - at;
      if (w == 4) {
        while (n + 32 <= most && std::memcmp(a + n, r + n, 32) == 0) n += 32;  // eight words a step
        for (std::uint32_t x, y; n < most; n += 4) {
          std::memcpy(&x, a + n, 4);
          std::memcpy(&y, r + n, 4);
          if (x != y) break;
        }
      } else {
        while (n < most && std::memcmp(a + n, r + n, w) == 0) n += w;
      }
      if (n > best) best = n, best_d = d;
    }
    if (best == 0) {
      for (std::size_t k = 0; k < w; ++k) fixed_literal(b, in[at + k]);
      at += w;
    } else {
      fixed_repeat(b, best, static_cast<unsigned>(best_d));
      at += best;
    }
    if (p.out.size() > limit) return false;
  }
  fixed_literal(b, 256);  // end of block
  if (!last) {
    b.put(0, 3);  // an empty stored block: not final, type 0, then LEN 0 and NLEN 0xffff
    b.align();
    for (const unsigned char c : {0x00, 0x00, 0xff, 0xff}) p.out.push_back(c);
  }
  b.align();
  p.used = p.out.size();
  return p.used <= limit;
}

void put_le32(std::ostream& out, std::uint32_t v) {
  const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                              static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 24)};
  out.write(reinterpret_cast<const char*>(b), 4);
}

}  // namespace

void write_gzip(std::ostream& out, const void* bytes, std::size_t size, int level, int threads,
                const IoProgress& progress, const GzipRuns& runs) {
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
        const std::size_t n = std::min(kGzipPiece, size - std::min(at, size));
        const bool last = i + 1 == pieces;
        // Runs first where asked for; a piece they do not shrink to a 16th goes to zlib.
        const bool by_runs = runs.word > 0 && size % runs.word == 0 && kGzipPiece % runs.word == 0 &&
                             run_piece(in, std::min(at, size), std::min(at, size) + n, last, runs, n / 16 + 64, work[k]);
        if (by_runs) work[k].crc = crc32(0L, in + std::min(at, size), static_cast<uInt>(n));
        else deflate_piece(in + std::min(at, size), n, last, level, work[k]);
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
