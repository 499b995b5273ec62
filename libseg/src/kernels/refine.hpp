// The refinement's kernels (section 3.3's scans, stages/refine.cpp and stages/refine_unknown.cpp):
// the slots, each level's versions, and how a table fills them.
//
// Voxel states are bytes (occseg::State: 0 free, 1 unknown, 2 occupied; no other value); bit rows
// are util/bit_rows.hpp's (64 voxels per word_t, voxel x at bit x % 64 of word x / 64, bits past a
// row's end 0). Every kernel takes a whole row (or the run up to the next boundary), so the
// indirect call is paid once per row.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"
#include "util/bit_rows.hpp"

namespace occseg::kernels {

using detail::word_t;

// The four cases of a window entered from state `from` (free or occupied), on bit masks of its
// voxels (bit k: voxel k; `all` its n bits): `occ` the voxels whose own state is occupied, `unk()`
// those whose own state is unknown (read only when needed). Returns the voxels that move to
// `from` (stages/refine.cpp states the cases). The occupied bits come first: where they show no
// voxel on `from`'s side (entering an object whose voxels are all occupied, or leaving one into
// space with none), the window is case (i) or (ii) whatever its unknown bits.
template <class Unknown>
inline std::uint64_t window_moves(std::uint64_t occ, std::uint64_t all, std::uint8_t from, Unknown&& unk) {
  constexpr std::uint8_t free_state = 0;
  if (from == free_state ? occ == all : occ == 0) return 0;
  const std::uint64_t unknown = unk() & ~occ, free = all & ~occ & ~unknown;
  const std::uint64_t for_from = from == free_state ? free : occ, for_into = from == free_state ? occ : free;
  if (!for_from) return 0;                  // (i), (ii)
  return for_into ? all & ~for_into : all;  // (iv) : (iii)
}

// What plane_row() did: bit w set where it wrote an occupied voxel into window row w; whether a
// window started.
struct PlaneRow {
  std::uint64_t occupied_rows = 0;
  bool started = false;
};

struct RefineKernels {
  // Step 2 (the free/occupied scans).
  // Whether some pair a[x], b[x] (x < n) is free/occupied or occupied/free.
  bool (*any_boundary)(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) = nullptr;
  // Whether some voxel of s[0, n) is occupied.
  bool (*any_occupied)(const std::uint8_t* s, std::size_t n) = nullptr;
  // A row st[0, len) scanned forward (step > 0: scan position q is voxel q, its pair st[q-1],
  // st[q]) or backward (position q is voxel len-1-q, its pair st[len-q], st[len-1-q]): the first
  // position at or after k (1 <= k) whose pair is free/occupied or occupied/free; len if none.
  std::size_t (*next_boundary)(const std::uint8_t* st, std::size_t k, std::size_t len, int step) = nullptr;
  // One row of a plane scan, lanes x < nx: the row before (prev) and the row (cur) in scan order,
  // skip[x] the voxels left in lane x's running window (0: none). Writes the lanes with no
  // running window whose pair prev[x], cur[x] is free/occupied or occupied/free to lanes[], in
  // increasing order, and returns their number; counts every other lane's skip down by one.
  std::size_t (*window_starts)(const std::uint8_t* prev, const std::uint8_t* cur, std::uint8_t* skip, std::size_t nx,
                               std::uint32_t* lanes) = nullptr;
  // One row of a plane scan, lanes x < nx, windows and all: the row before (prev) and the row
  // (cur) in scan order; window row w (w < rows: the line's rows left, at most the look-ahead,
  // 1 <= rows <= 64) at cur + w * rs, its own states' bit rows occ[w] and unk[w]; skip as for
  // window_starts. A lane that starts a window (window_starts' test) takes as its voxels cur[x]
  // and the voxels after it equal to it, at most rows; those window_moves() gives (from prev[x])
  // become prev[x], and its skip the window's voxels less one; every other lane counts down.
  PlaneRow (*plane_row)(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                        std::size_t nx, const word_t* const* occ, const word_t* const* unk) = nullptr;

  // Step 1 (the unknown growth on bit rows).
  // The bit rows of st[0, nx) == unknown and of st[0, nx) == free (all their words written).
  void (*pack_states)(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free) = nullptr;
  // The bit row of bytes[0, n) == v (all its words written).
  void (*pack_equal)(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) = nullptr;
  // st[x] = unknown where bit x of w is set, for x < nx; the other voxels are left as they are.
  void (*unpack_unknown)(const word_t* w, std::size_t nx, std::uint8_t* st) = nullptr;
  // st[x] = unknown where bit x of w is set, else cs[x / 8] (the state of the voxel's cell of 8),
  // for x < nx.
  void (*write_cells_row)(const std::uint8_t* cs, const word_t* w, std::size_t nx, std::uint8_t* st) = nullptr;
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_refine(RefineKernels& k, Isa cap);

// Each level's kernels (for select_refine(); a level without its own version of a slot uses the
// one below it). scalar/: plain C++, the meaning of every slot.
namespace scalar {
bool any_boundary(const std::uint8_t* a, const std::uint8_t* b, std::size_t n);
bool any_occupied(const std::uint8_t* s, std::size_t n);
std::size_t next_boundary(const std::uint8_t* st, std::size_t k, std::size_t len, int step);
std::size_t window_starts(const std::uint8_t* prev, const std::uint8_t* cur, std::uint8_t* skip, std::size_t nx,
                          std::uint32_t* lanes);
PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk);
void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free);
void unpack_unknown(const word_t* w, std::size_t nx, std::uint8_t* st);
void write_cells_row(const std::uint8_t* cs, const word_t* w, std::size_t nx, std::uint8_t* st);
}  // namespace scalar
namespace sse2 {
std::size_t next_boundary(const std::uint8_t* st, std::size_t k, std::size_t len, int step);
std::size_t window_starts(const std::uint8_t* prev, const std::uint8_t* cur, std::uint8_t* skip, std::size_t nx,
                          std::uint32_t* lanes);
PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk);
void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free);
void unpack_unknown(const word_t* w, std::size_t nx, std::uint8_t* st);
}  // namespace sse2
namespace avx2 {
bool any_boundary(const std::uint8_t* a, const std::uint8_t* b, std::size_t n);
bool any_occupied(const std::uint8_t* s, std::size_t n);
void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free);
void write_cells_row(const std::uint8_t* cs, const word_t* w, std::size_t nx, std::uint8_t* st);
PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk);
}  // namespace avx2
namespace avx512 {
PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk);
}  // namespace avx512

}  // namespace occseg::kernels
