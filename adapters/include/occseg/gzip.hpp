// gzip (RFC 1952) through zlib, for the compressed samples of NRRD files (`encoding: gzip`, what
// 3D Slicer writes by default and what `occseg segment` writes labels.nrrd as).
#pragma once
#include <cstddef>
#include <ostream>
#include <string>

#include "occseg/io_progress.hpp"

namespace occseg {

// Writes bytes[0, size) to `out` as one gzip member (one deflate stream, so every gzip reader
// reads it: zlib's gzread, teem, ITK, Python's gzip). The bytes are compressed in pieces of
// kGzipPiece bytes on up to `threads` threads (0: all cores) as pigz does: each piece is deflated
// on its own and ended by a full flush, so the pieces concatenate into one stream; the CRC-32 of
// the pieces is combined. The output depends only on the bytes and `level`, never on the thread
// count. At most 2 x threads pieces are held in memory at a time; each is written as soon as the
// pieces before it are. Throws Error(internal) if zlib fails (it does not for valid arguments),
// Error(no_memory) when zlib cannot allocate, Error(cancelled) when `progress` says so.
//
// With `runs` (word > 0), for data made of long runs of equal words (labels), each piece is first
// coded without zlib as repeats of whole words (a word equal to the one before it, or to the one
// `row` or `slice` words back, x fastest) in deflate's fixed Huffman codes, a pass at memory
// speed; a piece that this does not shrink to a 16th of its size is deflated by zlib instead.
// Either way the stream is plain deflate, and the output still depends only on the bytes,
// `level` and `runs`.
inline constexpr std::size_t kGzipPiece = std::size_t(1) << 22;
struct GzipRuns {
  std::size_t word = 0;   // bytes per word: a multiple of it is the data's size (else no runs)
  std::size_t row = 0;    // words per row (0: none)
  std::size_t slice = 0;  // words per slice (0: none)
};
void write_gzip(std::ostream& out, const void* bytes, std::size_t size, int level = 1, int threads = 0,
                const IoProgress& progress = {}, const GzipRuns& runs = {});

// Inflates gzip data (one member or several concatenated, as gunzip reads them; zlib data is
// accepted too) into exactly `size` bytes at `out`, never writing past them. Returns "" on
// success, else what is wrong, for a message: "the gzip data is truncated after 1234 of its
// bytes (5678 of the 10000 bytes the header promises were decompressed)", "the gzip data is
// corrupt (zlib: invalid distance too far back) ...", "the gzip data decompresses to more than
// the 10000 bytes the header promises" (decompression stops there: a zip bomb costs no more
// than the header's size), "the gzip data ends after 5678 of the 10000 bytes the header
// promises". Throws Error(no_memory) when zlib cannot allocate and Error(cancelled) when
// `progress` says so.
std::string gunzip_exact(const void* data, std::size_t data_size, void* out, std::size_t size,
                         const IoProgress& progress = {});

}  // namespace occseg
