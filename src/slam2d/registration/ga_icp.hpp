// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// GA + ICP hybrid: J. L. Martinez, J. Gonzalez, J. Morales, A. Mandow, A. J. Garcia-Cerezo,
// "Mobile robot motion estimation by 2D scan matching with genetic and iterative closest point
// algorithms", Journal of Field Robotics 23(1), 2006.
//
// A genetic algorithm searches the odometry error window for the pose with the lowest
// range-difference error, then point-to-point ICP refines it from there:
//   - chromosome: three binary genes, the offsets (dx, dy, dtheta) added to the guess's
//     coordinates, each `bits_per_gene` bits spread evenly over [-window, +window]
//                                                                       decode_chromosome, Eq. (1)
//   - fitness: the source scan's ranges against the target scan seen from the candidate pose.
//     Target points moved into the source frame (p = T^-1 q) fall into the source's beams by
//     bearing (the nearest per beam, as the sensor would see it); where a beam holds both a
//     source reading r_k and a projected range r'_k it overlaps, and
//       e(T) = (1 / N_o) sum_k min((r_k - r'_k)^2, c^2)                  Eq. (2)
//     over the N_o overlapping beams, c = max_range_difference.
//   - overlap criterion: a pose whose overlap N_o / N_source is below `min_overlap` is
//     infeasible (e = +inf).                                             Eq. (3)
//   - operators: elitism, tournament selection, one-point crossover, bit-flip mutation.
//   - refinement: match_icp (Besl & McKay point-to-point ICP, icp.hpp) from the GA's best pose
//     (or from the guess when the guess scores better).
// The source's beam grid (first bearing, spacing) is read off its points, which are in the
// sensor frame and in beam order; `angular_resolution` overrides the spacing. The equation numbers
// are this file's own (docs/methods/ga_icp.md maps them to the paper's description).
//
// Seeded: the same config (seed included) gives the identical result; the search is serial.
// MatchResult: the ICP stage's estimate, covariance (Censi, point-to-point), residual, inliers
// and degeneracy; `iterations` = GA generations + ICP iterations; `converged` is the ICP's.

#include <numbers>
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct GaIcpConfig {
  // Search window around the guess (the odometry error bounds), Eq. (1).
  double window_x = 0.5;
  double window_y = 0.5;
  double window_theta = 0.35;
  int bits_per_gene = 6;
  // Genetic algorithm.
  int population = 40;
  int generations = 25;
  double crossover_rate = 0.8;
  double mutation_rate = 0.03;
  int elite = 2;
  int tournament_size = 3;
  std::uint64_t seed = 1;
  // Fitness, Eq. (2)-(3).
  double max_range_difference = 0.5;
  double min_overlap = 0.3;
  double angular_resolution = 0.0;
  // ICP refinement (match_icp, point-to-point).
  int icp_max_iterations = 50;
  double icp_max_correspondence_distance = 1.0;
  int icp_min_correspondences = 10;
};

template <typename Fields>
void describe(Fields& f, GaIcpConfig& c) {
  f.number("window_x", c.window_x, "m", greater_than(0), "half-width of the x offset of the search window around the guess, Eq. (1)");
  f.number("window_y", c.window_y, "m", greater_than(0), "half-width of the y offset");
  f.number("window_theta", c.window_theta, "rad", open_closed(0, std::numbers::pi), "half-width of the heading offset");
  f.number("bits_per_gene", c.bits_per_gene, "1", between(2, 20), "bits of each of the three genes");
  f.number("population", c.population, "1", at_least(2), "chromosomes per generation");
  f.number("generations", c.generations, "1", at_least(1), "");
  f.number("crossover_rate", c.crossover_rate, "1", between(0, 1), "probability that a selected couple is crossed");
  f.number("mutation_rate", c.mutation_rate, "1", between(0, 1), "probability that a bit flips");
  f.number("elite", c.elite, "1", at_least(0), "best chromosomes copied unchanged, < population");
  f.number("tournament_size", c.tournament_size, "1", at_least(1), "chromosomes drawn per selection");
  f.number("seed", c.seed, "1", any_value(), "the random stream");
  f.number("max_range_difference", c.max_range_difference, "m", greater_than(0), "c: a beam's range difference is clipped here, Eq. (2)-(3)");
  f.number("min_overlap", c.min_overlap, "1", between(0, 1), "overlapping beams over source beams below which a pose is infeasible");
  f.number("angular_resolution", c.angular_resolution, "rad", at_least(0), "the source's beam spacing (0: inferred from the points)");
  f.number("icp_max_iterations", c.icp_max_iterations, "1", at_least(1), "the ICP refinement (match_icp, point-to-point)");
  f.number("icp_max_correspondence_distance", c.icp_max_correspondence_distance, "m", greater_than(0), "(match_icp's default)");
  f.number("icp_min_correspondences", c.icp_min_correspondences, "1", at_least(3), "");
}

/// Throws Error naming the first invalid field.
void validate(const GaIcpConfig& config);

/// The offsets (dx m, dy m, dtheta rad) a chromosome codes, Eq. (1): gene g is bits
/// [g b, (g + 1) b) of `chromosome` (x, y, theta from the least significant end), value k maps
/// to -w + 2 w k / (2^b - 1).
Eigen::Vector3d decode_chromosome(std::uint64_t chromosome, const GaIcpConfig& config);

struct RangeDifferenceScore {
  double error = std::numeric_limits<double>::infinity();  // m^2, Eq. (2); +inf when infeasible, Eq. (3)
  double overlap = 0.0;                                    // 1, overlapping beams over source beams
  std::size_t overlapping_beams = 0;
};

/// The range-difference metric of one source scan, Eq. (2)-(3): built once, scored per pose.
class RangeDifferenceMetric {
 public:
  /// `source` in its sensor frame and in beam order; `angular_resolution` (rad) 0 infers the spacing.
  RangeDifferenceMetric(const PointCloud2& source, const GaIcpConfig& config);

  /// The score of T_target_source: target points moved into the source frame against the
  /// source's ranges beam by beam.
  RangeDifferenceScore score(const PointCloud2& target, const SE2& T_target_source) const;

  std::size_t beams() const { return ranges_.size(); }
  double angular_resolution() const { return increment_; }

 private:
  /// The beam of a bearing in the source frame, or beams() when it falls outside the scan.
  std::size_t beam_of(double bearing) const;

  double first_bearing_ = 0.0;  // rad
  double increment_ = 0.0;      // rad, signed: the direction the scan turns
  std::vector<double> ranges_;  // m, per beam; 0 where the source has no reading
  std::size_t readings_ = 0;    // beams with a reading
  double max_range_difference_ = 0.5;
  double min_overlap_ = 0.3;
};

struct GaSearchResult {
  SE2 T_target_source;               // the best pose found (the guess when it scores better)
  RangeDifferenceScore score;        // its fitness
  int generations = 0;               // run
  std::size_t evaluations = 0;       // distinct chromosomes scored
};

/// The genetic search alone (no ICP).
GaSearchResult ga_search(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const GaIcpConfig& config = {});

/// The hybrid: ga_search, then match_icp from its pose (from the guess when no pose in the window
/// is feasible). Fewer than 3 points in either cloud: the guess, not converged, huge covariance.
MatchResult match_ga_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const GaIcpConfig& config = {});

}  // namespace slam2d
