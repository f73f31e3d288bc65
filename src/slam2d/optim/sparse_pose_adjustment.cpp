// SPDX-License-Identifier: BSD-3-Clause
// Sparse Pose Adjustment: K. Konolige, G. Grisetti, R. Kuemmerle, W. Burgard, B. Limketkai,
// R. Vincent, "Efficient sparse pose adjustment for 2D mapping", IROS 2010.
//
// Sec. IV of the paper: Levenberg-Marquardt, (H + lambda diag(H)) dx = -J^T Omega e (Eq. (4)),
// with H = J^T Omega J assembled block by block from the edge Jacobians straight into compressed
// column form (Sec. IV-B: for an edge (i, j), H_ii += J_i^T Omega J_i, H_ij += J_i^T Omega J_j,
// H_jj += J_j^T Omega J_j), and solved by sparse Cholesky. The block pattern of H and CHOLMOD's
// symbolic analysis depend only on the graph structure: built once, refilled every iteration.
#include "slam2d/optim/sparse_pose_adjustment.hpp"

#include <cholmod.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "slam2d/core/error.hpp"
#include "slam2d/optim/initial_guess.hpp"

namespace slam2d {

namespace {

constexpr double kMinLambda = 1e-12;  // 1: the damping never falls below this
constexpr double kMaxLambda = 1e16;   // 1: beyond, no step can lower the cost: stop

// Where a 3x3 block of H lives in the values of the compressed columns: entry (p, q) at
// values[base + q * stride + p].
struct BlockSlot {
  int base = -1;
  int stride = 0;
};

// The blocks an edge adds to (-1 base: that node is fixed or the edge adds nothing there).
struct EdgeSlots {
  int from_column = -1;  // block column of the `from` node, -1 when eliminated
  int to_column = -1;
  BlockSlot from_from, to_to, upper;  // upper: (min column, max column)
};

struct Cost {
  double robust = 0.0;  // sum of 2 rho(sqrt(e^T Omega e)) (robust edges) and e^T Omega e (others)
  double chi2 = 0.0;    // sum e^T Omega e
};

void add_block(std::vector<double>& values, const BlockSlot& slot, const Eigen::Matrix3d& block) {
  for (int q = 0; q < 3; ++q) {
    double* column = values.data() + slot.base + q * slot.stride;
    for (int p = 0; p < 3; ++p) column[p] += block(p, q);
  }
}

// Eq. (3), with the robust kernel on the robust edges for the cost LM descends.
Cost evaluate(const std::vector<PoseGraphEdge>& edges, const std::vector<SE2>& poses, const RobustKernel& kernel) {
  Cost cost;
  for (const PoseGraphEdge& edge : edges) {
    const double r2 = squared_error(edge, poses);
    cost.chi2 += r2;
    cost.robust += edge.robust ? 2.0 * kernel.cost(std::sqrt(r2)) : r2;
  }
  return cost;
}

// The kernel's weight of each edge at the graph's poses (1 for edges that are not robust).
std::vector<double> edge_weights(const PoseGraph& graph, const RobustKernel& kernel) {
  std::vector<double> weights(graph.edges.size(), 1.0);
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph.edges[k];
    if (!edge.robust) continue;
    weights[k] = kernel.weight(std::sqrt(squared_error(edge, graph.poses)));
  }
  return weights;
}

void check_edge(const PoseGraphEdge& edge, std::size_t k, int nodes) {
  const auto fail = [&](const std::string& what) {
    throw Error("sparse pose adjustment: edge " + std::to_string(k) + " (" + std::to_string(edge.from) + " -> " +
                std::to_string(edge.to) + "): " + what);
  };
  if (edge.from < 0 || edge.from >= nodes || edge.to < 0 || edge.to >= nodes) fail("node out of range");
  if (!edge.T_from_to.vector().allFinite() || !edge.information.allFinite()) fail("non-finite measurement");
  const double scale = edge.information.cwiseAbs().maxCoeff();
  if (!(edge.information - edge.information.transpose()).isZero(1e-9 * scale)) fail("information not symmetric");
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(edge.information, Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues().minCoeff() < -1e-9 * scale) fail("information not positive semi-definite");
}

void check_graph(const PoseGraph& graph) {
  check(graph.fixed.empty() || graph.fixed.size() == graph.size(),
        "sparse pose adjustment: `fixed` must be empty or have one flag per node");
  for (std::size_t node = 0; node < graph.size(); ++node) {
    if (!graph.poses[node].vector().allFinite()) {
      throw Error("sparse pose adjustment: node " + std::to_string(node) + " has a non-finite pose");
    }
  }
  const int nodes = static_cast<int>(graph.size());
  for (std::size_t k = 0; k < graph.edges.size(); ++k) check_edge(graph.edges[k], k, nodes);
}

}  // namespace

// CHOLMOD's state and the fixed block pattern of H for one graph structure.
struct SparsePoseAdjustment::Solver {
  Solver() {
    cholmod_start(&common);
    common.print = 0;  // failures are read from common.status
    common.quick_return_if_not_posdef = 1;
    // Simplicial LDL^T: with Debian's reference BLAS the supernodal factorisation is two to three
    // times slower on pose graphs (3x3 blocks, little fill).
    common.supernodal = CHOLMOD_SIMPLICIAL;
  }
  ~Solver() {
    release();
    cholmod_free_dense(&solution, &common);
    cholmod_free_dense(&workspace_y, &common);
    cholmod_free_dense(&workspace_e, &common);
    cholmod_finish(&common);
  }
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  int dimension() const { return 3 * columns; }

  /// Rebuilds the pattern and re-analyses unless the graph has the structure analysed last.
  void prepare(const PoseGraph& graph) {
    if (same_structure(graph)) return;
    release();
    remember_structure(graph);
    assign_columns(graph);
    build_pattern(graph);
    if (columns == 0) return;
    analyze();
  }

  /// H = sum J^T Omega J and b = sum J^T Omega e over the edges, IRLS-weighted (Sec. IV-B).
  void linearize(const PoseGraph& graph, const RobustKernel& kernel) {
    std::fill(hessian.begin(), hessian.end(), 0.0);
    gradient.setZero(dimension());
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      const EdgeSlots& slots = edge_slots[k];
      if (slots.from_column < 0 && slots.to_column < 0) continue;
      const PoseGraphEdge& edge = graph.edges[k];
      Eigen::Matrix3d J_from, J_to;
      const Eigen::Vector3d e = edge_error(edge, graph.poses[edge.from], graph.poses[edge.to], &J_from, &J_to);
      const double weight = edge.robust ? kernel.weight(std::sqrt(e.dot(edge.information * e))) : 1.0;
      const Eigen::Matrix3d Omega = weight * edge.information;
      const Eigen::Matrix3d JtO_from = J_from.transpose() * Omega;
      const Eigen::Matrix3d JtO_to = J_to.transpose() * Omega;
      if (slots.from_column >= 0) {
        add_block(hessian, slots.from_from, JtO_from * J_from);
        gradient.segment<3>(3 * slots.from_column) += JtO_from * e;
      }
      if (slots.to_column >= 0) {
        add_block(hessian, slots.to_to, JtO_to * J_to);
        gradient.segment<3>(3 * slots.to_column) += JtO_to * e;
      }
      if (slots.upper.base >= 0) {
        add_block(hessian, slots.upper, slots.from_column < slots.to_column ? Eigen::Matrix3d(JtO_from * J_to)
                                                                            : Eigen::Matrix3d(JtO_to * J_from));
      }
    }
    double trace = 0.0;
    for (int index : diagonal) trace += hessian[index];
    min_damping = 1e-6 * trace / std::max(dimension(), 1);
  }

  /// Eq. (4): step = -(H + lambda diag(H))^-1 b; false when the damped H is not positive definite.
  bool solve(double lambda) {
    auto* values = static_cast<double*>(matrix->x);
    std::copy(hessian.begin(), hessian.end(), values);
    for (int index : diagonal) values[index] += lambda * std::max(hessian[index], min_damping);
    step_valid = false;
    cholmod_factorize(matrix, factor, &common);
    check(common.status != CHOLMOD_OUT_OF_MEMORY, "sparse pose adjustment: out of memory");
    if (common.status == CHOLMOD_NOT_POSDEF || factor->minor < factor->n) return false;
    cholmod_dense rhs{};
    rhs.nrow = rhs.nzmax = rhs.d = static_cast<std::size_t>(dimension());
    rhs.ncol = 1;
    rhs.x = gradient.data();
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_solve2(CHOLMOD_A, factor, &rhs, nullptr, &solution, nullptr, &workspace_y, &workspace_e, &common);
    check(solution != nullptr, "sparse pose adjustment: CHOLMOD solve failed");
    step = -Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(solution->x), dimension());
    step_valid = step.allFinite();
    return step_valid;
  }

  /// For each candidate edge, e^T (Omega^-1 + J H^-1 J^T)^-1 e at the graph's poses, H the
  /// undamped Gauss-Newton matrix of the graph's edges (the poses' covariance); e^T Omega e where
  /// H cannot be factorised.
  std::vector<PredictedJoin> predicted_joins(const PoseGraph& graph, const RobustKernel& kernel,
                                             const std::vector<PoseGraphEdge>& candidates) {
    std::vector<PredictedJoin> result(candidates.size());
    for (std::size_t c = 0; c < candidates.size(); ++c) result[c].chi2 = squared_error(candidates[c], graph.poses);
    prepare(graph);
    if (columns == 0 || candidates.empty()) return result;
    linearize(graph, kernel);
    std::copy(hessian.begin(), hessian.end(), static_cast<double*>(matrix->x));
    cholmod_factorize(matrix, factor, &common);
    check(common.status != CHOLMOD_OUT_OF_MEMORY, "sparse pose adjustment: out of memory");
    if (common.status == CHOLMOD_NOT_POSDEF || factor->minor < factor->n) return result;
    constexpr std::size_t kBatch = 32;  // candidates per solve (3 right-hand sides each)
    const std::size_t n = static_cast<std::size_t>(dimension());
    cholmod_dense* rhs = cholmod_zeros(n, 3 * kBatch, CHOLMOD_REAL, &common);
    check(rhs != nullptr, "sparse pose adjustment: out of memory");
    for (std::size_t first = 0; first < candidates.size(); first += kBatch) {
      const std::size_t count = std::min(kBatch, candidates.size() - first);
      Eigen::Map<Eigen::MatrixXd> B(static_cast<double*>(rhs->x), static_cast<Eigen::Index>(n), 3 * kBatch);
      B.setZero();
      std::vector<std::array<Eigen::Matrix3d, 2>> jacobians(count);
      std::vector<Eigen::Vector3d> errors(count);
      for (std::size_t m = 0; m < count; ++m) {
        const PoseGraphEdge& edge = candidates[first + m];
        errors[m] = edge_error(edge, graph.poses[edge.from], graph.poses[edge.to], &jacobians[m][0], &jacobians[m][1]);
        const std::array<int, 2> nodes{edge.from, edge.to};
        for (int side = 0; side < 2; ++side) {
          const int column = column_of_node[static_cast<std::size_t>(nodes[side])];
          if (column >= 0) B.block<3, 3>(3 * column, 3 * static_cast<Eigen::Index>(m)) += jacobians[m][side].transpose();
        }
      }
      cholmod_dense* solved = cholmod_solve(CHOLMOD_A, factor, rhs, &common);
      check(solved != nullptr, "sparse pose adjustment: CHOLMOD solve failed");
      const Eigen::Map<const Eigen::MatrixXd> X(static_cast<const double*>(solved->x), static_cast<Eigen::Index>(n), 3 * kBatch);
      for (std::size_t m = 0; m < count; ++m) {
        const PoseGraphEdge& edge = candidates[first + m];
        Eigen::Matrix3d M = Eigen::Matrix3d::Zero();  // J H^-1 J^T
        const std::array<int, 2> nodes{edge.from, edge.to};
        for (int side = 0; side < 2; ++side) {
          const int column = column_of_node[static_cast<std::size_t>(nodes[side])];
          if (column >= 0) M += jacobians[m][side] * X.block<3, 3>(3 * column, 3 * static_cast<Eigen::Index>(m));
        }
        // (Omega^-1 + M)^-1 = (I + Omega M)^-1 Omega: no inverse of a semi-definite Omega.
        const Eigen::Vector3d y = (Eigen::Matrix3d::Identity() + edge.information * M).fullPivLu().solve(edge.information * errors[m]);
        PredictedJoin& join = result[first + m];
        join.chi2 = errors[m].dot(y);
        // The step that joining would take, H^-1 J^T (Omega^-1 + M)^-1 e = X y (first order).
        join.max_translation = join.max_turn = 0.0;
        for (int column = 0; column < columns; ++column) {
          const Eigen::Vector3d step = X.block<3, 3>(3 * column, 3 * static_cast<Eigen::Index>(m)) * y;
          join.max_translation = std::max(join.max_translation, step.head<2>().norm());
          join.max_turn = std::max(join.max_turn, std::abs(step.z()));
        }
      }
      cholmod_free_dense(&solved, &common);
    }
    cholmod_free_dense(&rhs, &common);
    return result;
  }

  /// The cost at x + dx (into `candidate`) for the damping lambda; infinite when the damped
  /// system cannot be solved.
  Cost try_step(const PoseGraph& graph, double lambda, const RobustKernel& kernel) {
    if (!solve(lambda)) return Cost{.robust = INFINITY, .chi2 = INFINITY};
    candidate = graph.poses;
    apply_step(candidate);
    return evaluate(graph.edges, candidate, kernel);
  }

  /// max |dx| over the coordinates (infinity when the last solve failed).
  double step_size() const { return step_valid ? step.lpNorm<Eigen::Infinity>() : INFINITY; }

  /// x <- x + dx on (x, y, theta) of every node in the system (the angle normalised).
  void apply_step(std::vector<SE2>& poses) const {
    for (std::size_t node = 0; node < poses.size(); ++node) {
      const int column = column_of_node[node];
      if (column >= 0) poses[node] = SE2::from_vector(poses[node].vector() + step.segment<3>(3 * column));
    }
  }

  int columns = 0;                  // block columns: the nodes optimised
  std::vector<SE2> candidate;       // the poses of the last step tried
  std::vector<int> column_of_node;  // -1: fixed, or not constrained by any edge

 private:
  bool same_structure(const PoseGraph& graph) const {
    if (!factor && columns > 0) return false;
    if (graph.size() != nodes || graph.edges.size() != endpoints.size() || graph.fixed.size() != fixed.size()) {
      return false;
    }
    for (std::size_t k = 0; k < endpoints.size(); ++k) {
      if (endpoints[k][0] != graph.edges[k].from || endpoints[k][1] != graph.edges[k].to) return false;
    }
    return graph.fixed == fixed;
  }

  void remember_structure(const PoseGraph& graph) {
    nodes = graph.size();
    fixed = graph.fixed;
    endpoints.resize(graph.edges.size());
    for (std::size_t k = 0; k < graph.edges.size(); ++k) endpoints[k] = {graph.edges[k].from, graph.edges[k].to};
  }

  // Fixed nodes are eliminated; so are nodes no edge ties to another node (H would be singular).
  void assign_columns(const PoseGraph& graph) {
    std::vector<bool> constrained(graph.size(), false);
    for (const PoseGraphEdge& edge : graph.edges) {
      if (edge.from != edge.to) constrained[edge.from] = constrained[edge.to] = true;
    }
    column_of_node.assign(graph.size(), -1);
    columns = 0;
    for (std::size_t node = 0; node < graph.size(); ++node) {
      if (constrained[node] && !graph.is_fixed(node)) column_of_node[node] = columns++;
    }
  }

  // The upper block triangle of H in compressed columns: per block column c, the blocks (r, c)
  // of the edges with r < c in increasing r, then the diagonal block; and each edge's slots.
  void build_pattern(const PoseGraph& graph) {
    std::vector<std::vector<int>>& rows_above = block_rows_above;
    rows_above.assign(columns, {});
    for (const PoseGraphEdge& edge : graph.edges) {
      const int a = column_of_node[edge.from];
      const int b = column_of_node[edge.to];
      if (a >= 0 && b >= 0 && a != b) rows_above[std::max(a, b)].push_back(std::min(a, b));
    }
    std::vector<int> column_start(columns + 1, 0);  // index of the column's first value
    for (int c = 0; c < columns; ++c) {
      auto& rows = rows_above[c];
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      column_start[c + 1] = column_start[c] + 9 * static_cast<int>(rows.size() + 1);
    }
    block_start.assign(columns + 1, 0);
    for (int c = 0; c < columns; ++c) block_start[c + 1] = block_start[c] + static_cast<int>(rows_above[c].size() + 1);
    const int n = dimension();
    matrix = cholmod_allocate_sparse(n, n, column_start[columns], 1, 1, 1, CHOLMOD_REAL, &common);
    check(matrix != nullptr, "sparse pose adjustment: out of memory");
    auto* column_pointers = static_cast<int*>(matrix->p);
    auto* row_indices = static_cast<int*>(matrix->i);
    diagonal.clear();
    for (int c = 0; c < columns; ++c) {
      const int blocks = static_cast<int>(rows_above[c].size()) + 1;
      for (int q = 0; q < 3; ++q) {
        int index = column_start[c] + 3 * blocks * q;
        column_pointers[3 * c + q] = index;
        for (int r : rows_above[c]) {
          for (int p = 0; p < 3; ++p) row_indices[index++] = 3 * r + p;
        }
        for (int p = 0; p < 3; ++p) row_indices[index++] = 3 * c + p;
        diagonal.push_back(index - 3 + q);
      }
    }
    column_pointers[n] = column_start[columns];
    hessian.assign(column_start[columns], 0.0);
    const auto slot = [&](int r, int c) {
      const auto& rows = rows_above[c];
      const int position = r == c ? static_cast<int>(rows.size())
                                  : static_cast<int>(std::lower_bound(rows.begin(), rows.end(), r) - rows.begin());
      const int stride = 3 * static_cast<int>(rows.size() + 1);
      return BlockSlot{column_start[c] + 3 * position, stride};
    };
    edge_slots.assign(graph.edges.size(), EdgeSlots{});
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      const int a = column_of_node[graph.edges[k].from];
      const int b = column_of_node[graph.edges[k].to];
      if (a == b) continue;  // both eliminated, or a self-loop (no gradient)
      EdgeSlots& slots = edge_slots[k];
      slots.from_column = a;
      slots.to_column = b;
      if (a >= 0) slots.from_from = slot(a, a);
      if (b >= 0) slots.to_to = slot(b, b);
      if (a >= 0 && b >= 0) slots.upper = slot(std::min(a, b), std::max(a, b));
    }
  }

  // The fill-reducing ordering (AMD) of the block pattern, one block per node, expanded to the
  // scalar columns: the same ordering quality at a ninth of the work, blocks kept together.
  void analyze() {
    cholmod_sparse* pattern = cholmod_allocate_sparse(columns, columns, block_start[columns], 1, 1, 1, CHOLMOD_PATTERN, &common);
    check(pattern != nullptr, "sparse pose adjustment: out of memory");
    auto* pointers = static_cast<int*>(pattern->p);
    auto* rows = static_cast<int*>(pattern->i);
    for (int c = 0; c <= columns; ++c) pointers[c] = block_start[c];
    for (int c = 0; c < columns; ++c) {
      int index = block_start[c];
      for (int r : block_rows_above[c]) rows[index++] = r;
      rows[index] = c;
    }
    std::vector<int> block_order(columns);
    cholmod_amd(pattern, nullptr, 0, block_order.data(), &common);
    cholmod_free_sparse(&pattern, &common);
    check(common.status >= CHOLMOD_OK, "sparse pose adjustment: CHOLMOD ordering failed");
    std::vector<int> order(dimension());
    for (int k = 0; k < columns; ++k) {
      for (int d = 0; d < 3; ++d) order[3 * k + d] = 3 * block_order[k] + d;
    }
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_GIVEN;
    factor = cholmod_analyze_p(matrix, order.data(), nullptr, 0, &common);
    check(factor != nullptr && common.status >= CHOLMOD_OK, "sparse pose adjustment: CHOLMOD analysis failed");
  }

  void release() {
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&matrix, &common);
  }

  cholmod_common common{};
  cholmod_sparse* matrix = nullptr;  // the damped H, upper triangle (stype 1)
  cholmod_factor* factor = nullptr;  // symbolic analysis kept while the structure holds
  cholmod_dense* solution = nullptr;
  cholmod_dense* workspace_y = nullptr;
  cholmod_dense* workspace_e = nullptr;
  std::vector<double> hessian;      // H (undamped), in the layout of matrix->x
  std::vector<int> diagonal;        // index of each diagonal entry in `hessian`
  Eigen::VectorXd gradient;         // b = J^T Omega e
  Eigen::VectorXd step;             // dx
  bool step_valid = false;          // the last solve gave a finite step
  double min_damping = 0.0;         // floor of diag(H) in the damping term
  std::vector<EdgeSlots> edge_slots;
  std::vector<std::vector<int>> block_rows_above;  // per block column, the block rows above the diagonal
  std::vector<int> block_start;                    // per block column, its first block

  // The structure analysed: node count, fixed flags, edge endpoints.
  std::size_t nodes = 0;
  std::vector<bool> fixed;
  std::vector<std::array<int, 2>> endpoints;
};

void validate(const SparsePoseAdjustmentConfig& config) { check_fields(config, "SparsePoseAdjustmentConfig"); }

SparsePoseAdjustment::SparsePoseAdjustment(const SparsePoseAdjustmentConfig& config)
    : config_(config), solver_(std::make_unique<Solver>()) {
  validate(config_);
}

SparsePoseAdjustment::~SparsePoseAdjustment() = default;
SparsePoseAdjustment::SparsePoseAdjustment(SparsePoseAdjustment&&) noexcept = default;
SparsePoseAdjustment& SparsePoseAdjustment::operator=(SparsePoseAdjustment&&) noexcept = default;

// The LM loop of Sec. IV: linearise, solve the damped system (Eq. (4)), keep the step if it lowers
// the (robust) cost and relax the damping, else raise the damping and solve again.
SparsePoseAdjustmentResult SparsePoseAdjustment::optimize(PoseGraph& graph) {
  return optimize(graph, config_.relative_tolerance);
}

SparsePoseAdjustmentResult SparsePoseAdjustment::optimize(PoseGraph& graph, double relative_tolerance) {
  check(relative_tolerance >= 0.0, "sparse pose adjustment: relative tolerance must be >= 0");
  const auto start = std::chrono::steady_clock::now();
  check_graph(graph);
  if (config_.loop_kernel.type == RobustKernelType::kTls) {
    // The last decisions by edge, for the edges that are still the graph's first ones (a caller
    // may take edges back, as graph SLAM does with a refused large correction).
    std::size_t kept = 0;
    while (kept < graduated_endpoints_.size() && kept < graph.edges.size() &&
           graduated_endpoints_[kept] == std::array<int, 2>{graph.edges[kept].from, graph.edges[kept].to}) {
      ++kept;
    }
    graduated_weights_.resize(std::min(kept, graduated_weights_.size()));
    SparsePoseAdjustmentResult result = optimize_graduated(graph, config_, graduated_weights_);
    graduated_weights_ = result.edge_weights;
    graduated_endpoints_.resize(graph.edges.size());
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      graduated_endpoints_[k] = {graph.edges[k].from, graph.edges[k].to};
    }
    return result;
  }
  if (!solver_) solver_ = std::make_unique<Solver>();
  Solver& solver = *solver_;
  solver.prepare(graph);

  SparsePoseAdjustmentResult result;
  Cost cost = evaluate(graph.edges, graph.poses, config_.loop_kernel);
  result.initial_chi2 = cost.chi2;
  // Warm start: the last damping, but never more than a fresh start's.
  double lambda = lambda_ > 0.0 ? std::min(lambda_, config_.initial_lambda) : config_.initial_lambda;
  bool linearized = false;
  result.converged = solver.columns == 0 || !(cost.robust > 0.0);  // nothing to optimise or to lower
  while (!result.converged && result.iterations < config_.max_iterations && lambda <= kMaxLambda) {
    if (!linearized) solver.linearize(graph, config_.loop_kernel);
    linearized = true;
    ++result.iterations;
    const Cost next = solver.try_step(graph, lambda, config_.loop_kernel);
    const double decrease = (cost.robust - next.robust) / cost.robust;
    if (decrease > 0.0) {
      graph.poses.swap(solver.candidate);
      cost = next;
      linearized = false;
      lambda = std::max(lambda * config_.lambda_down, kMinLambda);
    } else {
      lambda *= config_.lambda_up;
    }
    // Converged: the cost changes by less than the tolerance either way (a rejected step that
    // barely changes it is rounding at the minimum), or the step barely moves.
    result.converged = std::abs(decrease) < relative_tolerance || solver.step_size() <= config_.step_tolerance;
  }
  lambda_ = lambda;
  result.final_chi2 = cost.chi2;
  result.edge_weights = edge_weights(graph, config_.loop_kernel);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::vector<PredictedJoin> SparsePoseAdjustment::predicted_joins(const PoseGraph& graph,
                                                                 const std::vector<PoseGraphEdge>& candidates) {
  check_graph(graph);
  const int nodes = static_cast<int>(graph.size());
  for (std::size_t k = 0; k < candidates.size(); ++k) check_edge(candidates[k], k, nodes);
  if (!solver_) solver_ = std::make_unique<Solver>();
  return solver_->predicted_joins(graph, config_.loop_kernel, candidates);
}

SparsePoseAdjustmentResult optimize_pose_graph(PoseGraph& graph, const SparsePoseAdjustmentConfig& config) {
  SparsePoseAdjustment spa(config);
  return spa.optimize(graph);
}

StartedOptimization optimize_pose_graph(PoseGraph& graph, const SparsePoseAdjustmentConfig& config,
                                        InitialGuessChoice initial) {
  StartedOptimization started;
  started.given_chi2 = chi2(graph);
  if (initial == InitialGuessChoice::kGiven) {
    started.result = optimize_pose_graph(graph, config);
    return started;
  }
  const bool from_tree = initial == InitialGuessChoice::kSpanningTree;
  PoseGraph start = from_tree ? with_spanning_tree_poses(graph) : with_orientations_first_poses(graph);
  started.estimate_chi2 = chi2(start);
  started.start = from_tree ? InitialGuessChoice::kSpanningTree : InitialGuessChoice::kOrientationsFirst;
  if (initial == InitialGuessChoice::kBetter && !(started.estimate_chi2 < started.given_chi2)) {
    started.start = InitialGuessChoice::kGiven;
    started.result = optimize_pose_graph(graph, config);
    return started;
  }
  started.result = optimize_pose_graph(start, config);
  if (initial == InitialGuessChoice::kBoth) {
    const SparsePoseAdjustmentResult given = optimize_pose_graph(graph, config);
    const double seconds = started.result.seconds + given.seconds;
    if (given.final_chi2 <= started.result.final_chi2) {
      started.result = given;
      started.start = InitialGuessChoice::kGiven;
    }
    started.result.seconds = seconds;
  }
  if (started.start != InitialGuessChoice::kGiven) graph.poses = std::move(start.poses);
  return started;
}

}  // namespace slam2d
