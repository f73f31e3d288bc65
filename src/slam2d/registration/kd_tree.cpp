// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/kd_tree.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <utility>

namespace slam2d {
namespace {

// nanoflann's dataset adaptor: the caller's points, read in place.
struct PointsAdaptor {
  const std::vector<Point2>* points;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t index, std::size_t dim) const { return (*points)[index][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box& /*box*/) const {
    return false;  // let nanoflann compute it
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointsAdaptor>, PointsAdaptor,
                                                 2, std::size_t>;

}  // namespace

struct KdTree2::Index {
  PointsAdaptor adaptor;
  Tree tree;
  Index(const std::vector<Point2>& points, int leaf_size)
      : adaptor{&points},
        tree(2, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(static_cast<std::size_t>(std::max(1, leaf_size)))) {}
};

KdTree2::KdTree2(const std::vector<Point2>& points, int leaf_size)
    : index_(std::make_unique<Index>(points, leaf_size)) {}
KdTree2::~KdTree2() = default;
KdTree2::KdTree2(KdTree2&&) noexcept = default;
KdTree2& KdTree2::operator=(KdTree2&&) noexcept = default;

std::size_t KdTree2::size() const { return index_->adaptor.points->size(); }
const std::vector<Point2>& KdTree2::points() const { return *index_->adaptor.points; }

Neighbor KdTree2::nearest(const Point2& query) const {
  Neighbor result{size(), 0.0};
  if (size() == 0) return result;
  nanoflann::KNNResultSet<double, std::size_t> results(1);
  results.init(&result.index, &result.squared_distance);
  index_->tree.findNeighbors(results, query.data(), nanoflann::SearchParams());
  return result;
}

std::size_t KdTree2::nearest_k(const Point2& query, std::size_t k, std::vector<Neighbor>& out) const {
  k = std::min(k, size());
  out.resize(k);
  if (k == 0) return 0;
  thread_local std::vector<std::size_t> indices;
  thread_local std::vector<double> distances;
  indices.resize(k);
  distances.resize(k);
  nanoflann::KNNResultSet<double, std::size_t> results(k);
  results.init(indices.data(), distances.data());
  index_->tree.findNeighbors(results, query.data(), nanoflann::SearchParams());
  const std::size_t found = results.size();
  out.resize(found);
  for (std::size_t i = 0; i < found; ++i) out[i] = {indices[i], distances[i]};
  return found;
}

std::vector<Neighbor> KdTree2::nearest_k(const Point2& query, std::size_t k) const {
  std::vector<Neighbor> out;
  nearest_k(query, k, out);
  return out;
}

std::vector<Neighbor> KdTree2::within_radius(const Point2& query, double radius) const {
  std::vector<std::pair<std::size_t, double>> matches;
  if (size() == 0 || !(radius > 0.0)) return {};
  index_->tree.radiusSearch(query.data(), radius * radius, matches, nanoflann::SearchParams(32, 0.0F, true));
  std::vector<Neighbor> out;
  out.reserve(matches.size());
  for (const auto& [index, distance] : matches) out.push_back({index, distance});
  return out;
}

}  // namespace slam2d
