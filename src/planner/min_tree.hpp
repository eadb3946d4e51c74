// A fixed-size tournament tree (segment tree) of doubles: set one leaf in O(log n), read the
// minimum of all leaves in O(1) and its index in O(log n). Memory is allocated once at
// construction; set/min/argmin never allocate. Empty leaves hold +infinity.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace cncore::planner {

class MinTree {
 public:
  static constexpr double kEmpty = std::numeric_limits<double>::infinity();

  explicit MinTree(std::size_t leaves) {
    while (size_ < leaves) size_ <<= 1;
    nodes_.assign(2 * size_, kEmpty);
  }

  std::size_t leaves() const { return size_; }
  double at(std::size_t i) const { return nodes_[size_ + i]; }
  double min() const { return nodes_[1]; }

  void set(std::size_t i, double value) {
    std::size_t k = size_ + i;
    nodes_[k] = value;
    for (k >>= 1; k != 0; k >>= 1) {
      const double m = nodes_[2 * k] <= nodes_[2 * k + 1] ? nodes_[2 * k] : nodes_[2 * k + 1];
      if (nodes_[k] == m) break;  // nothing above changes
      nodes_[k] = m;
    }
  }

  // Index of a leaf holding min() (meaningless when the tree is empty).
  std::size_t argmin() const {
    std::size_t k = 1;
    while (k < size_) k = nodes_[2 * k] <= nodes_[2 * k + 1] ? 2 * k : 2 * k + 1;
    return k - size_;
  }

 private:
  std::size_t size_ = 1;
  std::vector<double> nodes_;
};

}  // namespace cncore::planner
