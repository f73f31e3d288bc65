// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/correlative.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinPoints = 3;
constexpr int kMaxSteps = 1 << 20;                   // half-width of the window, in steps, per axis
constexpr double kMaxRotatedPoints = 1LL << 28;      // angles x points kept in memory
constexpr std::size_t kMaxSourcePoints = 1 << 23;    // 255 n stays an int
constexpr double kNegligibleResponse = 1e-3;       // p relative to the best pose's, Eq. (3)

/// ceil(log2(value)) for value >= 1.
int ceil_log2(long long value) {
  return value <= 1 ? 0 : static_cast<int>(std::bit_width(static_cast<unsigned long long>(value - 1)));
}

/// Cells per linear step: linear_step as a whole multiple of the resolution (0: one cell).
int step_cells(double linear_step, double resolution) {
  if (linear_step == 0.0) return 1;
  const double ratio = linear_step / resolution;
  const double cells = std::round(ratio);
  check(cells >= 1.0 && cells <= 1e6 && std::abs(ratio - cells) <= 1e-6 * ratio,
        "CorrelativeConfig: linear_step (" + std::to_string(linear_step) +
            " m) must be a whole multiple of the grid resolution (" + std::to_string(resolution) + " m)");
  return static_cast<int>(cells);
}

int half_steps(double half_width, double step) {
  const double n = std::floor(half_width / step + 1e-9);
  check(n <= kMaxSteps, "CorrelativeConfig: the window spans more than 2^20 steps per side");
  return static_cast<int>(n);
}

/// The pooled level that bounds a block of 2^height steps of `cells` cells: its cells span
/// (2^height - 1) cells + 1.
int level_for_height(int height, int cells) { return ceil_log2((((1LL << height) - 1) * cells) + 1); }

/// Branch-and-bound's top blocks: about 2 x 2 of them cover the window's translations.
int root_height(int n) { return std::max(0, ceil_log2(2LL * n + 1) - 1); }

// ---- The discrete search space (Olson Sec. III-C) --------------------------------------------

struct Window {
  int nx = 0, ny = 0, nk = 0;  // half-widths in steps: i in [-nx, nx], j in [-ny, ny], k in [-nk, nk]
  int cells = 1;               // grid cells per linear step
  double linear = 0.0;         // m per step
  double angular = 0.0;        // rad per step
  int bnb_height = 0;          // height of branch-and-bound's top blocks
  int max_height = 0;          // highest block the grid's levels bound
};

double farthest_point(const PointCloud2& cloud) {
  double r2 = 0.0;
  for (const Point2& p : cloud.points) r2 = std::max(r2, p.squaredNorm());
  return std::sqrt(r2);
}

Window make_window(const CorrelativeGrid& grid, const PointCloud2& source, const CorrelativeConfig& config) {
  Window w;
  w.cells = step_cells(config.linear_step, grid.resolution());
  w.linear = w.cells * grid.resolution();
  w.angular = config.angular_step;
  if (w.angular == 0.0) {  // the farthest point moves one linear step (a chord of length `linear`)
    const double r = farthest_point(source);
    w.angular = std::acos(std::clamp(1.0 - w.linear * w.linear / (2.0 * r * r), -1.0, 1.0));
  }
  w.nx = half_steps(config.window_x, w.linear);
  w.ny = half_steps(config.window_y, w.linear);
  w.nk = half_steps(config.window_theta, w.angular);
  check((2.0 * w.nk + 1.0) * static_cast<double>(source.size()) <= kMaxRotatedPoints,
        "CorrelativeConfig: too many angles for this source cloud (raise angular_step or narrow window_theta)");
  while (w.max_height < 30 && level_for_height(w.max_height + 1, w.cells) < grid.levels()) ++w.max_height;
  w.bnb_height = std::min(w.max_height, root_height(std::max(w.nx, w.ny)));
  return w;
}

// ---- The source rotated once per angle, as integer cell offsets -------------------------------

struct Rotation {
  std::vector<std::int32_t> offsets;  // stored index of each point's cell at translation (0, 0)
  std::vector<CellIndex> clamped;     // cells of the points whose reach leaves the stored raster
};

struct PoseIndex {
  int k = 0, j = 0, i = 0;  // angle, y and x steps from the guess
};

/// Tie key: the squared distance from the guess, in steps.
long long tie_key(const PoseIndex& p) {
  return static_cast<long long>(p.i) * p.i + static_cast<long long>(p.j) * p.j + static_cast<long long>(p.k) * p.k;
}

class Scorer {
 public:
  Scorer(const CorrelativeGrid& grid, const PointCloud2& source, const SE2& guess, const Window& window)
      : grid_(grid), source_(source), guess_(guess), w_(window) {
    const double per_metre = 1.0 / grid_.resolution();
    scaled_source_.reserve(source_.size());
    for (const Point2& p : source_.points) scaled_source_.push_back(per_metre * p);
    guess_in_cells_ = per_metre * (guess_.translation() - grid_.geometry().origin);
    const auto angles = static_cast<std::size_t>(2 * w_.nk + 1);
    rotations_.resize(angles);
    cos_sin_.resize(angles);
    for (int k = -w_.nk; k <= w_.nk; ++k) {
      const double theta = guess_.theta() + k * w_.angular;
      cos_sin_[static_cast<std::size_t>(k + w_.nk)] = {std::cos(theta), std::sin(theta)};
      rotate(k);
    }
  }

  const Window& window() const { return w_; }
  const CorrelativeGrid& grid() const { return grid_; }
  long long evaluations() const { return evaluations_; }

  /// Eq. (2) on level `level`: the sum of the scores of the points' cells, translation (i, j)
  /// steps from the guess's, at angle k. On level 0 the exact score, above it a bound of the
  /// translations [i, i + 2^h) x [j, j + 2^h) with level = level_for_height(h).
  int score(int k, int j, int i, int level) const {
    ++evaluations_;
    const Rotation& r = rotations_[static_cast<std::size_t>(k + w_.nk)];
    const std::uint8_t* data = grid_.level_data(level);
    const int dx = i * w_.cells;
    const int dy = j * w_.cells;
    const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(dy) * grid_.stride() + dx;
    int sum = 0;
    for (const std::int32_t offset : r.offsets) sum += data[offset + shift];
    for (const CellIndex& c : r.clamped) sum += grid_.score(level, c.x + dx, c.y + dy);
    return sum;
  }

  /// The pose of a window index.
  SE2 pose(const PoseIndex& p) const {
    return {guess_.translation() + w_.linear * Eigen::Vector2d(p.i, p.j), guess_.theta() + p.k * w_.angular};
  }

  /// The level-0 cell of source point n at pose p (the cells score() reads).
  CellIndex cell(std::size_t n, const PoseIndex& p) const {
    const CellIndex c = cell_at(rotated_in_cells(n, p.k));
    return {c.x + p.i * w_.cells, c.y + p.j * w_.cells};
  }
  /// False for a point so far from the grid that its cell index is not representable.
  bool representable(std::size_t n, int k) const { return representable(rotated_in_cells(n, k)); }

 private:
  /// Source point n at angle k, translation (0, 0), in cells from the grid's origin:
  /// (R(theta_k) p + t_guess - origin) / resolution, without a division per point.
  Eigen::Vector2d rotated_in_cells(std::size_t n, int k) const {
    const Eigen::Vector2d& cs = cos_sin_[static_cast<std::size_t>(k + w_.nk)];
    const Point2& p = scaled_source_[n];
    return Eigen::Vector2d(cs.x() * p.x() - cs.y() * p.y(), cs.y() * p.x() + cs.x() * p.y()) + guess_in_cells_;
  }
  static bool representable(const Eigen::Vector2d& q) {
    constexpr double kLimit = GridGeometry::kMaxCellIndex / 2;
    return std::abs(q.x()) <= kLimit && std::abs(q.y()) <= kLimit;  // false for NaN
  }
  static CellIndex cell_at(const Eigen::Vector2d& q) {
    return {GridGeometry::floor_to_int(q.x()), GridGeometry::floor_to_int(q.y())};
  }

  void rotate(int k) {
    Rotation& r = rotations_[static_cast<std::size_t>(k + w_.nk)];
    r.offsets.resize(source_.size());
    // A cell is read at every translation of the window when [c - reach, c + reach] stays in
    // the stored raster.
    const int reach_x = w_.nx * w_.cells;
    const int reach_y = w_.ny * w_.cells;
    const int pad = grid_.padding();
    const int x_min = reach_x - pad, x_end = grid_.width() + pad - reach_x;
    const int y_min = reach_y - pad, y_end = grid_.height() + pad - reach_y;
    std::size_t inside = 0;
    for (std::size_t n = 0; n < source_.size(); ++n) {
      const Eigen::Vector2d q = rotated_in_cells(n, k);
      if (!representable(q)) continue;  // 0 at every pose
      const CellIndex c = cell_at(q);
      if (c.x >= x_min && c.x < x_end && c.y >= y_min && c.y < y_end) {
        r.offsets[inside++] = static_cast<std::int32_t>(grid_.stored_index(c.x, c.y));
      } else {
        r.clamped.push_back(c);
      }
    }
    r.offsets.resize(inside);
  }

  const CorrelativeGrid& grid_;
  const PointCloud2& source_;
  SE2 guess_;
  Window w_;
  std::vector<Rotation> rotations_;
  std::vector<Eigen::Vector2d> cos_sin_;  // of each angle
  std::vector<Point2> scaled_source_;     // cells, the source points / resolution
  Eigen::Vector2d guess_in_cells_;        // cells, (t_guess - origin) / resolution
  mutable long long evaluations_ = 0;
};

// ---- The best pose and its total order --------------------------------------------------------

struct Best {
  PoseIndex pose;
  int score = -1;
  long long key = LLONG_MAX;

  /// Higher score, then smaller tie key, then smaller (k, j, i).
  bool improved_by(int s, long long k, const PoseIndex& p) const {
    if (s != score) return s > score;
    if (k != key) return k < key;
    return std::tie(p.k, p.j, p.i) < std::tie(pose.k, pose.j, pose.i);
  }
  void consider(int s, const PoseIndex& p) {
    const long long k = tie_key(p);
    if (improved_by(s, k, p)) *this = {p, s, k};
  }
};

/// A block of translations [i, i_end] x [j, j_end] at angle k, with the bound of its poses.
struct Block {
  PoseIndex low;  // k, lowest j and i
  int height = 0;
  int bound = 0;
  long long min_key = 0;  // the smallest tie key in the block
};

long long min_square(int a, int b) {
  if (a <= 0 && b >= 0) return 0;
  const long long m = std::min(std::abs(a), std::abs(b));
  return m * m;
}

Block make_block(const Scorer& scorer, const PoseIndex& low, int height) {
  const Window& w = scorer.window();
  const int span = (1 << height) - 1;
  Block b{low, height, 0, 0};
  b.min_key = min_square(low.i, std::min(low.i + span, w.nx)) + min_square(low.j, std::min(low.j + span, w.ny)) +
              static_cast<long long>(low.k) * low.k;
  b.bound = scorer.score(low.k, low.j, low.i, level_for_height(height, w.cells));
  return b;
}

/// Could a pose of the block beat (or tie-break) the best? Exact: bounds are integer sums.
bool may_beat(const Block& b, const Best& best) {
  return b.bound > best.score || (b.bound == best.score && b.min_key <= best.key);
}

bool block_order(const Block& a, const Block& b) {
  if (a.bound != b.bound) return a.bound > b.bound;
  if (a.min_key != b.min_key) return a.min_key < b.min_key;
  return std::tie(a.low.k, a.low.j, a.low.i) < std::tie(b.low.k, b.low.j, b.low.i);
}

/// Blocks of 2^height x 2^height translations tiling the window, at every angle, best first.
std::vector<Block> tile_window(const Scorer& scorer, int height) {
  const Window& w = scorer.window();
  const int side = 1 << height;
  std::vector<Block> blocks;
  for (int k = -w.nk; k <= w.nk; ++k) {
    for (int j = -w.ny; j <= w.ny; j += side) {
      for (int i = -w.nx; i <= w.nx; i += side) blocks.push_back(make_block(scorer, {k, j, i}, height));
    }
  }
  std::sort(blocks.begin(), blocks.end(), block_order);
  return blocks;
}

// ---- Olson Sec. III-D: the response distribution ----------------------------------------------

/// Eq. (3): moments of p = exp(log-likelihood) over the scored poses, streamed: the sums are kept
/// relative to the highest score seen, rescaled when it rises. Index units (steps).
class ResponseMoments {
 public:
  explicit ResponseMoments(const CorrelativeGrid& grid)
      : scale_(0.5 * grid.config().truncation * grid.config().truncation / kMaxCellScore) {}

  /// p of a score relative to p of `reference`.
  double weight(int score, int reference) const { return std::exp(scale_ * (score - reference)); }

  void add(const PoseIndex& p, int score) {
    if (score > top_) {
      const double rescale = top_ == INT_MIN ? 0.0 : std::exp(scale_ * (top_ - score));
      s_ *= rescale;
      u_ *= rescale;
      K_ *= rescale;
      top_ = score;
    }
    const double weight = std::exp(scale_ * (score - top_));
    const Eigen::Vector3d x(p.i, p.j, p.k);
    s_ += weight;
    u_ += weight * x;
    K_ += weight * x * x.transpose();
  }

  /// Sigma = K / s - u u^T / s^2 in (x, y, theta), plus the quantisation of one step.
  Covariance3 covariance(const Window& w) const {
    Eigen::Matrix3d cov = K_ / s_ - (u_ / s_) * (u_ / s_).transpose();
    const Eigen::Vector3d step(w.linear, w.linear, w.angular);
    cov = step.asDiagonal() * cov * step.asDiagonal();
    cov.diagonal() += step.cwiseProduct(step) / 12.0;
    const std::array<int, 3> searched{w.nx, w.ny, w.nk};
    for (int a = 0; a < 3; ++a) {
      if (searched[static_cast<std::size_t>(a)] == 0) {  // not searched: the match says nothing
        cov.row(a).setZero();
        cov.col(a).setZero();
        cov(a, a) = kUnknownVariance;
      }
    }
    return 0.5 * (cov + cov.transpose());
  }

 private:
  double scale_;  // log-likelihood per score unit, Eq. (1)
  int top_ = INT_MIN;
  double s_ = 0.0;
  Eigen::Vector3d u_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d K_ = Eigen::Matrix3d::Zero();
};

// ---- The three searches -----------------------------------------------------------------------

/// Olson Sec. III-C: every pose; each angle's rotated source slides over the translations.
Best search_exhaustive(const Scorer& scorer, ResponseMoments& moments) {
  const Window& w = scorer.window();
  Best best;
  for (int k = -w.nk; k <= w.nk; ++k) {
    for (int j = -w.ny; j <= w.ny; ++j) {
      for (int i = -w.nx; i <= w.nx; ++i) {
        const int s = scorer.score(k, j, i, 0);
        best.consider(s, {k, j, i});
        moments.add({k, j, i}, s);
      }
    }
  }
  return best;
}

/// Olson Sec. IV: bound every low-resolution voxel, then search the voxels at full resolution in
/// order of bound while the bound can still beat the best pose found.
Best search_multi_resolution(const Scorer& scorer, int voxel_steps) {
  const Window& w = scorer.window();
  const int height = std::min(ceil_log2(voxel_steps), w.max_height);
  Best best;
  for (const Block& voxel : tile_window(scorer, height)) {
    if (!may_beat(voxel, best)) {
      if (voxel.bound < best.score) break;  // sorted by bound: no later voxel can beat it
      continue;
    }
    const int span = (1 << height) - 1;
    for (int j = voxel.low.j; j <= std::min(voxel.low.j + span, w.ny); ++j) {
      for (int i = voxel.low.i; i <= std::min(voxel.low.i + span, w.nx); ++i) {
        best.consider(scorer.score(voxel.low.k, j, i, 0), {voxel.low.k, j, i});
      }
    }
  }
  return best;
}

/// Hess 2016 Algorithm 3: depth first, children in order of bound, pruned by the best score.
void branch(const Scorer& scorer, std::span<const Block> blocks, Best& best) {
  const Window& w = scorer.window();
  for (const Block& block : blocks) {
    if (!may_beat(block, best)) {
      if (block.bound < best.score) return;
      continue;
    }
    if (block.height == 0) {  // a single pose: its bound is its score
      best.consider(block.bound, block.low);
      continue;
    }
    const int half = 1 << (block.height - 1);
    std::array<Block, 4> children;
    std::size_t count = 0;
    for (int dj : {0, half}) {
      for (int di : {0, half}) {
        const PoseIndex low{block.low.k, block.low.j + dj, block.low.i + di};
        if (low.j <= w.ny && low.i <= w.nx) children[count++] = make_block(scorer, low, block.height - 1);
      }
    }
    for (std::size_t a = 1; a < count; ++a) {  // insertion sort of at most 4 children
      for (std::size_t b = a; b > 0 && block_order(children[b], children[b - 1]); --b) std::swap(children[b], children[b - 1]);
    }
    branch(scorer, std::span<const Block>(children.data(), count), best);
  }
}

Best search_branch_and_bound(const Scorer& scorer) {
  Best best;
  const std::vector<Block> roots = tile_window(scorer, scorer.window().bnb_height);
  branch(scorer, roots, best);
  return best;
}

/// The fast searches' covariance support (Sec. III-D over the neighbourhood of the best pose):
/// a box around it scored at full resolution, each side doubled while the response on its face
/// is not negligible, up to `radius` steps and the window's edges. A peaked response keeps the
/// box at +-1 step; a flat direction (a corridor's axis) grows it as far as allowed.
void score_neighbourhood(const Scorer& scorer, const Best& best, int radius, ResponseMoments& moments) {
  const Window& w = scorer.window();
  const std::array<int, 3> centre{best.pose.k, best.pose.j, best.pose.i};
  const std::array<int, 3> half{w.nk, w.ny, w.nx};
  std::array<int, 3> low{}, high{};  // extent of the box below and above the best pose, in steps
  auto grow = [&](int extent, int limit) { return std::min({std::max(1, 2 * extent), radius, limit}); };
  for (std::size_t a = 0; a < 3; ++a) {
    low[a] = grow(0, centre[a] + half[a]);
    high[a] = grow(0, half[a] - centre[a]);
  }
  std::unordered_map<long long, int> scores;  // by pose, so that growing re-scores nothing
  auto for_each_pose = [&](auto&& visit) {
    for (int k = centre[0] - low[0]; k <= centre[0] + high[0]; ++k) {
      for (int j = centre[1] - low[1]; j <= centre[1] + high[1]; ++j) {
        for (int i = centre[2] - low[2]; i <= centre[2] + high[2]; ++i) {
          const long long key = ((static_cast<long long>(k) << 21) + j) * (1LL << 21) + i;
          auto [it, inserted] = scores.try_emplace(key, 0);
          if (inserted) it->second = scorer.score(k, j, i, 0);
          visit(PoseIndex{k, j, i}, it->second);
        }
      }
    }
  };
  for (bool grown = true; grown;) {
    std::array<bool, 3> low_face{}, high_face{};  // the face holds a non-negligible response
    for_each_pose([&](const PoseIndex& p, int score) {
      if (moments.weight(score, best.score) < kNegligibleResponse) return;
      const std::array<int, 3> x{p.k, p.j, p.i};
      for (std::size_t a = 0; a < 3; ++a) {
        low_face[a] = low_face[a] || x[a] == centre[a] - low[a];
        high_face[a] = high_face[a] || x[a] == centre[a] + high[a];
      }
    });
    grown = false;
    for (std::size_t a = 0; a < 3; ++a) {
      const int new_low = low_face[a] ? grow(low[a], centre[a] + half[a]) : low[a];
      const int new_high = high_face[a] ? grow(high[a], half[a] - centre[a]) : high[a];
      grown = grown || new_low != low[a] || new_high != high[a];
      low[a] = new_low;
      high[a] = new_high;
    }
  }
  for_each_pose([&](const PoseIndex& p, int score) { moments.add(p, score); });
}

// ---- The result ---------------------------------------------------------------------------------

MatchResult failed_match(const SE2& guess) {
  MatchResult result;
  result.T_target_source = guess;
  result.converged = false;
  result.degenerate = true;
  return result;
}

bool strictly_inside(const Window& w, const PoseIndex& p) {
  auto inside = [](int index, int n) { return n == 0 || std::abs(index) < n; };
  return inside(p.i, w.nx) && inside(p.j, w.ny) && inside(p.k, w.nk);
}

/// Inliers, residual (table distances) and degeneracy (nearest target points) at the best pose.
void describe_fit(const Scorer& scorer, const PointCloud2& source, const Best& best, const CorrelativeConfig& config,
                  MatchResult& result) {
  const CorrelativeGrid& grid = scorer.grid();
  std::vector<Correspondence> pairs;
  double squared_sum = 0.0;
  for (std::size_t n = 0; n < source.size(); ++n) {
    if (!scorer.representable(n, best.pose.k)) continue;
    const CellIndex c = scorer.cell(n, best.pose);
    const int s = grid.score(0, c.x, c.y);
    if (s == 0) continue;
    const double d = grid.distance_of_score(s);
    squared_sum += d * d;
    const Neighbor nearest = grid.tree().nearest(result.T_target_source * source.points[n]);
    pairs.push_back({n, nearest.index, kNoPoint, 1.0});
  }
  result.inliers = pairs.size();
  result.residual = pairs.empty() ? 0.0 : std::sqrt(squared_sum / static_cast<double>(pairs.size()));
  const DegeneracyConfig degeneracy{.min_eigenvalue_ratio = config.min_eigenvalue_ratio};
  apply(analyze_degeneracy(grid.target(), source, result.T_target_source, pairs, degeneracy), result);
}

MatchResult make_result(const Scorer& scorer, const PointCloud2& source, const Best& best,
                        const ResponseMoments& moments, const CorrelativeConfig& config) {
  MatchResult result;
  result.T_target_source = scorer.pose(best.pose);
  result.covariance = moments.covariance(scorer.window());
  result.iterations = static_cast<int>(std::min<long long>(scorer.evaluations(), INT_MAX));
  const double normalised = static_cast<double>(best.score) / (kMaxCellScore * static_cast<double>(source.size()));
  result.converged = strictly_inside(scorer.window(), best.pose) && normalised >= config.min_score;
  describe_fit(scorer, source, best, config, result);
  return result;
}

void check_inputs(const PointCloud2& source, const SE2& guess) {
  check(guess.vector().allFinite(), "match_correlative: the guess is not finite");
  check(source.size() <= kMaxSourcePoints, "match_correlative: more than 2^23 source points");
  for (const Point2& p : source.points) check(p.allFinite(), "match_correlative: the source cloud has a non-finite point");
}

}  // namespace

void validate(const CorrelativeConfig& config) {
  check_fields(config, "CorrelativeConfig");
  validate(CorrelativeGridConfig{.resolution = config.resolution,
                                 .sigma = config.sigma,
                                 .truncation = config.truncation,
                                 .max_segment_length = config.max_segment_length,
                                 .levels = 1});
  check(std::has_single_bit(static_cast<unsigned>(config.low_resolution_steps)),
        "CorrelativeConfig: low_resolution_steps must be a power of two, got " + std::to_string(config.low_resolution_steps));
}

CorrelativeGridConfig correlative_grid_config(const CorrelativeConfig& config) {
  validate(config);
  CorrelativeGridConfig grid{.resolution = config.resolution,
                             .sigma = config.sigma,
                             .truncation = config.truncation,
                             .max_segment_length = config.max_segment_length,
                             .levels = config.levels};
  if (grid.levels != 0) return grid;
  const int cells = step_cells(config.linear_step, config.resolution);
  const double linear = cells * config.resolution;
  const int n = std::max(half_steps(config.window_x, linear), half_steps(config.window_y, linear));
  int height = 0;
  if (config.search == CorrelativeSearch::kBranchAndBound) height = root_height(n);
  if (config.search == CorrelativeSearch::kMultiResolution) height = ceil_log2(config.low_resolution_steps);
  grid.levels = std::min(16, level_for_height(height, cells) + 1);
  return grid;
}

MatchResult match_correlative(const CorrelativeGrid& grid, const PointCloud2& source, const SE2& T_target_source_guess,
                              const CorrelativeConfig& config) {
  validate(config);
  check_inputs(source, T_target_source_guess);
  if (source.size() < kMinPoints || grid.empty()) return failed_match(T_target_source_guess);
  const Window window = make_window(grid, source, config);      // Sec. III-C: the discrete poses
  const Scorer scorer(grid, source, T_target_source_guess, window);  // the source rotated once per angle
  ResponseMoments moments(grid);
  Best best;
  switch (config.search) {
    case CorrelativeSearch::kExhaustive:
      best = search_exhaustive(scorer, moments);
      break;
    case CorrelativeSearch::kMultiResolution:
      best = search_multi_resolution(scorer, config.low_resolution_steps);
      break;
    case CorrelativeSearch::kBranchAndBound:
      best = search_branch_and_bound(scorer);
      break;
  }
  if (config.search != CorrelativeSearch::kExhaustive) score_neighbourhood(scorer, best, config.covariance_radius, moments);
  return make_result(scorer, source, best, moments, config);  // Sec. III-D: covariance; fit and degeneracy
}

MatchResult match_correlative(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                              const CorrelativeConfig& config) {
  const CorrelativeGridConfig grid_config = correlative_grid_config(config);
  check_inputs(source, T_target_source_guess);
  if (source.size() < kMinPoints || target.empty()) return failed_match(T_target_source_guess);
  return match_correlative(CorrelativeGrid(target, grid_config), source, T_target_source_guess, config);
}

}  // namespace slam2d
