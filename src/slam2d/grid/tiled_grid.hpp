// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// TiledGrid: an unbounded 2D grid of cells that grows as cells are written.
//
// Cells live in square tiles of kTileSize x kTileSize cells, allocated on the first write into
// them, so memory follows the explored area (the tile table itself costs one pointer per tile of
// the bounding box). Tiles are held by std::shared_ptr: copying a grid copies the tile table and
// shares every tile, and a write into a shared tile copies that tile first (copy-on-write), so a
// particle filter can copy its maps cheaply. Reads of unwritten cells return the default value
// and allocate nothing.
//
// Threads: as for a standard container, const calls on one grid may run concurrently, and a
// non-const call needs the grid to itself. Different grids may be read and written from different
// threads at the same time even when they share tiles (particles of a filter updated in parallel);
// the argument is at mutable_tile(). Copying or destroying a grid counts as a const call on the
// grids it shares tiles with (it only moves reference counts, which are atomic).

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/thread_sanitizer.hpp"
#include "slam2d/grid/grid_geometry.hpp"
#include "slam2d/grid/ray_casting.hpp"

namespace slam2d {

template <typename Cell, int kLog2TileSize = 6>
class TiledGrid {
 public:
  static constexpr int kTileSize = 1 << kLog2TileSize;  // cells along each side of a tile
  static constexpr int kCellsPerTile = kTileSize * kTileSize;
  static constexpr long long kMaxTableSlots = 1LL << 22;  // tiles in the table's bounding box
  static constexpr int kMaxFixedPointRay = 46340;         // cells; 2 n^2 < 2^32 (see update_ray)
  struct Tile {
    std::array<Cell, kCellsPerTile> cells;  // row-major, row 0 at the tile's smallest y
  };

  explicit TiledGrid(const Cell& default_value = Cell{}) : default_value_(default_value) {}

  /// The tile holding a cell (floor division by kTileSize; arithmetic shifts floor negatives).
  static CellIndex tile_of(CellIndex cell) { return {cell.x >> kLog2TileSize, cell.y >> kLog2TileSize}; }
  /// The position of a cell in its tile's `cells` array.
  static int offset_in_tile(CellIndex cell) {
    return ((cell.y & (kTileSize - 1)) << kLog2TileSize) | (cell.x & (kTileSize - 1));
  }

  /// The cell's value, or the default value if its tile was never written. Never allocates.
  const Cell& at(CellIndex cell) const {
    const Tile* tile = find_tile(tile_of(cell));
    return tile != nullptr ? tile->cells[offset_in_tile(cell)] : default_value_;
  }
  /// A writable reference: allocates (or un-shares) the tile and adds the cell to the bounding box.
  Cell& mutable_at(CellIndex cell) {
    touched_.extend(cell);
    return mutable_tile(tile_of(cell))[offset_in_tile(cell)];
  }

  /// The cells of a tile for writing: allocated filled with the default value on first use and
  /// copied first when shared with another grid. The caller reports the cells it writes with
  /// mark_touched() (mutable_at does it itself).
  Cell* mutable_tile(CellIndex tile);
  /// The cells of a tile, or nullptr if it was never written.
  const Tile* find_tile(CellIndex tile) const {
    const int tx = tile.x - table_origin_.x;
    const int ty = tile.y - table_origin_.y;
    if (tx < 0 || ty < 0 || tx >= table_width_ || ty >= table_height_) return nullptr;
    return table_[static_cast<std::size_t>(ty) * table_width_ + tx].get();
  }
  /// Calls visit(Cell&) on the cells of the Bresenham ray from `from` up to, not including, `to`:
  /// the cells of for_each_cell_before() (ray_casting.hpp), in the same order. Tiles are allocated
  /// and un-shared as the ray enters them and the cells join the bounding box. This is the fast
  /// path of ray casting: it walks offsets inside a tile with a fixed-point minor coordinate (no
  /// error term chained from cell to cell) and looks a tile up only when the ray enters it. Both
  /// cells must lie within GridGeometry::kMaxCellIndex of the origin.
  template <typename Visit>
  void update_ray(CellIndex from, CellIndex to, Visit&& visit);

  /// Adds cells written through mutable_tile() to the bounding box.
  void mark_touched(const CellBox& cells) { touched_.extend(cells); }
  /// Grows the tile table to cover every tile of `cells` (allocates no tile).
  void reserve(const CellBox& cells);

  /// Bounding box of all cells written so far (empty for a fresh grid).
  const CellBox& bounding_box() const { return touched_; }
  std::size_t tile_count() const;
  /// True when both grids hold the very same tile object for this cell (not yet copied on write).
  bool shares_tile_with(const TiledGrid& other, CellIndex cell) const {
    const Tile* tile = find_tile(tile_of(cell));
    return tile != nullptr && tile == other.find_tile(tile_of(cell));
  }
  /// Bytes held by this grid's tiles (shared tiles included) and tile table.
  std::size_t memory_bytes() const {
    return sizeof(*this) + table_.capacity() * sizeof(std::shared_ptr<Tile>) + tile_count() * sizeof(Tile);
  }
  const Cell& default_value() const { return default_value_; }

  /// Calls f(CellIndex first_cell, const Tile&) for every allocated tile.
  template <typename F>
  void for_each_tile(F&& f) const;

 private:
  std::shared_ptr<Tile>& slot(CellIndex tile) {
    return table_[static_cast<std::size_t>(tile.y - table_origin_.y) * table_width_ + (tile.x - table_origin_.x)];
  }
  void grow_table(const CellBox& tiles);
  /// floor(numerator 2^32 / denominator) for 0 <= numerator <= denominator <= kMaxFixedPointRay,
  /// through a double division corrected to the exact floor (a 64-bit integer division is slow).
  static std::uint64_t fixed_point_slope(int numerator, int denominator) {
    const std::uint64_t scaled = static_cast<std::uint64_t>(numerator) << 32;
    const auto d = static_cast<std::uint64_t>(denominator);
    auto slope = static_cast<std::uint64_t>(static_cast<double>(scaled) / static_cast<double>(denominator));
    if (slope * d > scaled) --slope;
    else if ((slope + 1) * d <= scaled) ++slope;
    return slope;
  }

  Cell default_value_;
  CellIndex table_origin_{0, 0};  // tile index of table_[0]
  int table_width_ = 0;           // tiles
  int table_height_ = 0;          // tiles
  std::vector<std::shared_ptr<Tile>> table_;  // row-major; null for tiles never written
  CellBox touched_;
};

template <typename Cell, int kLog2TileSize>
Cell* TiledGrid<Cell, kLog2TileSize>::mutable_tile(CellIndex tile) {
  if (find_tile(tile) == nullptr) {
    CellBox box;
    box.extend(tile);
    grow_table(box);
  }
  std::shared_ptr<Tile>& entry = slot(tile);
  if (!entry) {
    entry = std::make_shared<Tile>();
    entry->cells.fill(default_value_);
  } else if (entry.use_count() > 1) {
    std::shared_ptr<Tile> copy = std::make_shared<Tile>(*entry);  // copy-on-write
    tsan_release(entry.get());  // what the count's decrement below releases, declared to TSan
    entry = std::move(copy);
  } else {
    // This grid is the tile's only owner: it is written in place. Why that is safe while other
    // threads work on other grids that shared this tile until a moment ago:
    //  - A tile's owners are the tables of grids. Its count rises only when a grid is copied, and
    //    the grid copied is then an owner, so a count that has reached 1 stays 1 until this thread
    //    copies this grid; no other thread can reach the tile any more (they read tiles only
    //    through their own grid's table, never through a pointer kept from another grid).
    //  - While two grids own the tile, neither writes it (each sees a count >= 2 and copies), so
    //    shared tiles are only ever read, and concurrent reads and copies of them are fine.
    //  - What remains is ordering: another thread's last reads of the tile (its copy, its
    //    matching) must happen before our writes. That thread released its reference with the
    //    count's decrement, a release operation (libstdc++: acq_rel fetch_add; later decrements
    //    continue its release sequence). use_count() is a relaxed load that read that decrement's
    //    value (1), so this acquire fence makes the decrement synchronise with us: everything that
    //    thread did with the tile happens before the writes below (C++20 [atomics.fences]/4).
    // Two grids un-sharing one tile at the same time both copy it (both saw 2), or one copies and
    // then the other writes in place (it saw 1); either way every grid gets the same cells, so the
    // values do not depend on the schedule, only which grid keeps the old tile object does.
    std::atomic_thread_fence(std::memory_order_acquire);
    tsan_acquire(entry.get());  // what the fence acquires, declared to TSan (it ignores fences)
  }
  return entry->cells.data();
}

template <typename Cell, int kLog2TileSize>
template <typename Visit>
void TiledGrid<Cell, kLog2TileSize>::update_ray(CellIndex from, CellIndex to, Visit&& visit) {
  constexpr int kMask = kTileSize - 1;
  const int dx = to.x - from.x;
  const int dy = to.y - from.y;
  const bool x_major = std::abs(dx) >= std::abs(dy);
  const int d_major = x_major ? std::abs(dx) : std::abs(dy);  // cells to visit
  const int d_minor = x_major ? std::abs(dy) : std::abs(dx);
  if (d_major == 0) return;
  if (d_major > kMaxFixedPointRay) {  // beyond the exact range of the fixed-point walk below
    for_each_cell_before(from, to, [&](CellIndex cell) { visit(mutable_at(cell)); });
    return;
  }
  // Bresenham's minor offset k_i = floor((2 i d_minor + d_major) / (2 d_major)) as a 32.32
  // fixed-point sum: position_i = i * floor(d_minor 2^32 / d_major) + 2^31 + d_major. Its
  // rounding error lies in (0, d_major] units, below the 2^32 / (2 d_major) gap to the next
  // integer whenever 2 d_major^2 < 2^32: then k_i = position_i >> 32 exactly.
  const std::uint64_t slope = fixed_point_slope(d_minor, d_major);
  std::uint64_t position = (std::uint64_t{1} << 31) + static_cast<std::uint64_t>(d_major);
  const int s_major = (x_major ? dx : dy) >= 0 ? 1 : -1;
  const int s_minor = (x_major ? dy : dx) >= 0 ? 1 : -1;
  const int major_offset = x_major ? s_major : s_major * kTileSize;  // offsets inside a tile
  const int minor_offset = x_major ? s_minor * kTileSize : s_minor;
  const int major_from = x_major ? from.x : from.y;
  const int minor_from = x_major ? from.y : from.x;
  const auto last_minor = static_cast<int>((position + static_cast<std::uint64_t>(d_major - 1) * slope) >> 32);
  touched_.extend(from);
  touched_.extend(x_major ? CellIndex{from.x + s_major * (d_major - 1), from.y + s_minor * last_minor}
                          : CellIndex{from.x + s_minor * last_minor, from.y + s_major * (d_major - 1)});
  for (int i = 0; i < d_major;) {
    // Enter the tile of cell i, walk while the ray stays in it.
    const int k_first = static_cast<int>(position >> 32);
    const int major = major_from + s_major * i;
    const int minor = minor_from + s_minor * k_first;
    const int local_major = major & kMask;
    const int local_minor = minor & kMask;
    Cell* cells = mutable_tile(tile_of(x_major ? CellIndex{major, minor} : CellIndex{minor, major}));
    const int k_last = k_first + (s_minor > 0 ? kMask - local_minor : local_minor);  // last k inside the tile
    const int count = std::min(s_major > 0 ? kTileSize - local_major : local_major + 1, d_major - i);
    const int base = x_major ? (local_minor << kLog2TileSize) | local_major : (local_major << kLog2TileSize) | local_minor;
    // Cell j of the segment is cells[base + j major_offset + (k_j - k_first) minor_offset] with
    // k_j = (position + j slope) >> 32, while k_j <= k_last. slope <= 2^32, so k steps by 0 or 1
    // per cell: the index follows it, stepping along the minor axis when position crosses the
    // next multiple of 2^32 (the same cells in the same order as computing k_j for each j).
    std::ptrdiff_t cell = base;  // an index, not a pointer: after the last cell it may lie outside the tile
    std::uint64_t next_minor = (static_cast<std::uint64_t>(k_first) + 1) << 32;  // where k becomes k_first + 1
    int minor_steps_left = k_last - k_first;
    int j = 0;
    while (j < count) {
      visit(cells[cell]);
      ++j;
      position += slope;
      cell += major_offset;
      if (position >= next_minor) {
        if (minor_steps_left == 0) break;  // the next cell lies in the next tile along the minor axis
        --minor_steps_left;
        next_minor += std::uint64_t{1} << 32;
        cell += minor_offset;
      }
    }
    i += j;
  }
}

template <typename Cell, int kLog2TileSize>
void TiledGrid<Cell, kLog2TileSize>::reserve(const CellBox& cells) {
  if (cells.empty()) return;
  CellBox tiles;
  tiles.extend(tile_of(cells.min));
  tiles.extend(tile_of(cells.max));
  grow_table(tiles);
}

template <typename Cell, int kLog2TileSize>
void TiledGrid<Cell, kLog2TileSize>::grow_table(const CellBox& tiles) {
  CellBox current;
  if (table_width_ > 0) {
    current.extend(table_origin_);
    current.extend(CellIndex{table_origin_.x + table_width_ - 1, table_origin_.y + table_height_ - 1});
  }
  if (current.contains(tiles.min) && current.contains(tiles.max)) return;
  CellBox wanted = current;
  wanted.extend(tiles);
  // Grow by at least half the current size on each side that grows, so that a grid explored
  // one tile at a time is re-laid out O(log n) times.
  const int margin_x = current.width() / 2;
  const int margin_y = current.height() / 2;
  if (!current.empty()) {
    if (wanted.min.x < current.min.x) wanted.min.x = std::min(wanted.min.x, current.min.x - margin_x);
    if (wanted.max.x > current.max.x) wanted.max.x = std::max(wanted.max.x, current.max.x + margin_x);
    if (wanted.min.y < current.min.y) wanted.min.y = std::min(wanted.min.y, current.min.y - margin_y);
    if (wanted.max.y > current.max.y) wanted.max.y = std::max(wanted.max.y, current.max.y + margin_y);
  }
  const long long slots = static_cast<long long>(wanted.width()) * wanted.height();
  check(slots <= kMaxTableSlots, "TiledGrid: the grid would span more than 2^22 tiles");
  std::vector<std::shared_ptr<Tile>> table(static_cast<std::size_t>(slots));
  for (int ty = 0; ty < table_height_; ++ty) {
    for (int tx = 0; tx < table_width_; ++tx) {
      const std::size_t to = static_cast<std::size_t>(table_origin_.y + ty - wanted.min.y) * wanted.width() +
                             (table_origin_.x + tx - wanted.min.x);
      table[to] = std::move(table_[static_cast<std::size_t>(ty) * table_width_ + tx]);
    }
  }
  table_ = std::move(table);
  table_origin_ = wanted.min;
  table_width_ = wanted.width();
  table_height_ = wanted.height();
}

template <typename Cell, int kLog2TileSize>
std::size_t TiledGrid<Cell, kLog2TileSize>::tile_count() const {
  std::size_t count = 0;
  for (const auto& tile : table_) count += tile ? 1 : 0;
  return count;
}

template <typename Cell, int kLog2TileSize>
template <typename F>
void TiledGrid<Cell, kLog2TileSize>::for_each_tile(F&& f) const {
  for (int ty = 0; ty < table_height_; ++ty) {
    for (int tx = 0; tx < table_width_; ++tx) {
      const Tile* tile = table_[static_cast<std::size_t>(ty) * table_width_ + tx].get();
      if (tile != nullptr) f(CellIndex{(table_origin_.x + tx) * kTileSize, (table_origin_.y + ty) * kTileSize}, *tile);
    }
  }
}

}  // namespace slam2d
