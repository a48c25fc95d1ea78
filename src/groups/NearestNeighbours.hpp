// The k nearest neighbours of points in an open or periodic box, by a k-d tree (HOP's densities and hops).
#pragma once
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/PeriodicWrap.hpp"
#include "core/Vec3.hpp"

namespace fountain::groups {

// A k-d tree over a point set, searched at nearest periodic images. (nanoflann, the usual
// library, prunes with per-axis plane distances that a periodic box breaks; the boxes here
// are bounding boxes inside [0, L), whose image distances are exact bounds.) Read-only once
// built: any number of threads may search it at once.
class NearestNeighbours {
 public:
  // box > 0: periodic box [0, box)^3 (points must lie in it); box = 0: open. The points are
  // read, not copied: they must outlive the tree.
  NearestNeighbours(std::span<const Vec3> points, double box);

  struct Neighbour {
    double distance2;
    std::uint32_t index;
    bool operator<(const Neighbour& o) const { return distance2 < o.distance2 || (distance2 == o.distance2 && index < o.index); }
  };
  // The k nearest points to x (fewer if the set is smaller), nearest first, ties by index:
  // the answer is the same whatever the tree's shape. A point of the set finds itself first.
  std::vector<Neighbour> nearest(const Vec3& x, std::size_t k) const;
  // The same into `found`, with `stack` for the search: buffers a caller reuses across queries.
  using SearchStack = std::vector<std::pair<std::int32_t, double>>;
  void nearest(const Vec3& x, std::size_t k, std::vector<Neighbour>& found, SearchStack& stack) const;

  // The points in the tree's order (its leaves one after another): queries made in this
  // order find their neighbours in cache.
  const std::vector<std::uint32_t>& order() const { return order_; }

  // b - a at the nearest image.
  Vec3 separation(const Vec3& a, const Vec3& b) const { return nearest_image(a, b, box_); }

 private:
  struct Node {
    Vec3 lo, hi;                 // bounding box of its points
    std::uint32_t first, count;  // its points: order_[first, first + count)
    std::int32_t left = -1, right = -1;
  };
  std::int32_t build(std::uint32_t first, std::uint32_t count);
  double box_distance2(const Node& n, const Vec3& x) const;

  std::span<const Vec3> points_;
  double box_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace fountain::groups
