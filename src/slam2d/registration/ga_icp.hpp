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
//   - matching: the source scan's ranges against the target scan seen from the candidate pose.
//     Target points moved into the source frame (p = T^-1 q) fall into the source's beams by
//     bearing (the nearest per beam, as the sensor would see it); a source reading r_k is
//     matched when its beam holds a projected range r'_k with |r_k - r'_k| <= E_max
//     (`max_range_difference`).
//   - matching index: I = N_m / N, the matched readings over the source's N readings, and the
//     mean squared difference of the matched ones, e_m^2 = (1 / N_m) sum (r_k - r'_k)^2.
//   - fitness (lower is fitter): every source reading costs its squared difference when matched
//     and E_max^2 when not (no target there, or too far):
//       e(T) = I e_m^2 + (1 - I) E_max^2                                  Eq. (2)
//     A pose that explains few readings cannot score well however closely it fits those.
//   - feasibility: a pose whose matching index is below `min_matching_index` is infeasible
//     (e = +inf).                                                        Eq. (3)
//   - operators: elitism, tournament selection, one-point crossover, bit-flip mutation.
//   - refinement: match_icp (Besl & McKay point-to-point ICP, icp.hpp) from the GA's best pose
//     (or from the guess when the guess scores better), its association gate reduced from the
//     ICP alone's to what the GA left: E_icp = clamp(k e_m, E_min, E_max_icp), k e_m being k
//     times the RMS range difference of the matched readings at that pose.    Eq. (4)
//     Pairs farther apart than the GA's residual error are then outliers (what one scan sees and
//     the other does not), not the pose error ICP has to remove.
// The source's beam grid (first bearing, spacing) is read off its points, which are in the
// sensor frame and in beam order; `angular_resolution` overrides the spacing. The equation numbers
// are this file's own (docs/methods/ga_icp.md maps them to the paper's description).
//
// Seeded: the same config (seed included) gives the identical result; the search is serial.
// MatchResult: the ICP stage's estimate, covariance (Censi, point-to-point), residual, inliers
// and degeneracy; `iterations` = GA generations + ICP iterations; `converged` is the ICP's.
//
// What is the paper's and what is ours: the paper's GA searches the odometry error window with
// short binary chromosomes and a fitness built on the matched points and the matching index,
// then runs ICP with a smaller E_max than ICP alone uses. The exact forms above (the range
// difference along beams, Eq. (2), the gate of Eq. (4) and its factor) are this library's reading;
// docs/methods/ga_icp.md says which figures were measured.

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
  // Matching and fitness, Eq. (2)-(3).
  double max_range_difference = 0.5;  // m, E_max of the GA: a reading matches within this
  double min_matching_index = 0.3;    // 1: poses matching fewer readings are infeasible
  double angular_resolution = 0.0;
  // ICP refinement (match_icp, point-to-point), its gate reduced from the GA's result, Eq. (4).
  int icp_max_iterations = 50;
  double icp_max_correspondence_distance = 1.0;  // m, the gate's upper bound (ICP alone's gate)
  double icp_gate_factor = 3.0;                  // 1, k of Eq. (4); 0: no reduction (the upper bound)
  double icp_min_correspondence_distance = 0.1;  // m, the gate's lower bound
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
  f.number("max_range_difference", c.max_range_difference, "m", greater_than(0), "E_max of the GA: a reading matches when its range difference is at most this; an unmatched one costs its square, Eq. (2)");
  f.number("min_matching_index", c.min_matching_index, "1", between(0, 1), "matched readings over source readings below which a pose is infeasible, Eq. (3)");
  f.number("angular_resolution", c.angular_resolution, "rad", at_least(0), "the source's beam spacing (0: inferred from the points)");
  f.number("icp_max_iterations", c.icp_max_iterations, "1", at_least(1), "the ICP refinement (match_icp, point-to-point)");
  f.number("icp_max_correspondence_distance", c.icp_max_correspondence_distance, "m", greater_than(0), "upper bound of the ICP stage's gate (match_icp's default gate), Eq. (4)");
  f.number("icp_gate_factor", c.icp_gate_factor, "1", at_least(0), "the ICP gate is this times the RMS range difference of the matched readings at the GA's pose, Eq. (4); 0: the upper bound");
  f.number("icp_min_correspondence_distance", c.icp_min_correspondence_distance, "m", greater_than(0), "lower bound of the ICP stage's gate, Eq. (4)");
  f.number("icp_min_correspondences", c.icp_min_correspondences, "1", at_least(3), "");
}

/// Throws Error naming the first invalid field.
void validate(const GaIcpConfig& config);

/// The offsets (dx m, dy m, dtheta rad) a chromosome codes, Eq. (1): gene g is bits
/// [g b, (g + 1) b) of `chromosome` (x, y, theta from the least significant end), value k maps
/// to -w + 2 w k / (2^b - 1).
Eigen::Vector3d decode_chromosome(std::uint64_t chromosome, const GaIcpConfig& config);

struct RangeDifferenceScore {
  double error = std::numeric_limits<double>::infinity();  // m^2, e of Eq. (2); +inf when infeasible, Eq. (3)
  double matching_index = 0.0;                             // 1, I: matched readings over source readings
  std::size_t matched_readings = 0;                        // N_m
  double matched_rms = 0.0;                                // m, e_m: RMS range difference of the matched readings
};

/// The matching of one source scan, Eq. (2)-(3): built once, scored per pose.
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
  double min_matching_index_ = 0.3;
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

/// The ICP stage's gate after a search, Eq. (4): clamp(icp_gate_factor e_m, icp_min_correspondence_distance,
/// icp_max_correspondence_distance) at the search's pose; the upper bound when that pose is infeasible
/// or icp_gate_factor is 0.
double icp_gate(const GaSearchResult& search, const GaIcpConfig& config);

/// The hybrid: ga_search, then match_icp from its pose (from the guess when no pose in the window
/// is feasible) with the gate of Eq. (4). Fewer than 3 points in either cloud: the guess, not
/// converged, huge covariance.
MatchResult match_ga_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const GaIcpConfig& config = {});

}  // namespace slam2d
