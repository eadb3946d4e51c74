// A fixed-size tournament tree (segment tree) of doubles: set one leaf in O(log n), read the
// minimum of all leaves in O(1), its index in O(log n) and the minimum over a range of leaves in
// O(log n). Memory is allocated once at construction (2·n doubles: the compact bottom-up layout,
// leaf i at node n + i, node k = min(node 2k, node 2k + 1); for a minimum every leaf still
// reaches the root, so n need not be a power of two); set/min/argmin/min_range never allocate.
// Empty leaves hold +infinity.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace cncore::planner {

class MinTree {
 public:
  static constexpr double kEmpty = std::numeric_limits<double>::infinity();

  explicit MinTree(std::size_t leaves) : size_(leaves > 0 ? leaves : 1) {
    nodes_.assign(2 * size_, kEmpty);
  }

  std::size_t leaves() const { return size_; }
  double at(std::size_t i) const { return nodes_[size_ + i]; }
  // With one leaf the root is the leaf itself (node 1 = leaf 0).
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

  // The minimum of leaves [lo, hi) (kEmpty when the range is empty).
  double min_range(std::size_t lo, std::size_t hi) const {
    double out = kEmpty;
    for (lo += size_, hi += size_; lo < hi; lo >>= 1, hi >>= 1) {
      if (lo & 1) {
        out = nodes_[lo] < out ? nodes_[lo] : out;
        ++lo;
      }
      if (hi & 1) {
        --hi;
        out = nodes_[hi] < out ? nodes_[hi] : out;
      }
    }
    return out;
  }

 private:
  std::size_t size_;
  std::vector<double> nodes_;
};

// `width` tournament trees over the same leaves, stored node-major (node k holds the width
// values of every tree, contiguous): updating one leaf in all of them walks one path of
// log2(n) nodes of width·8 bytes each instead of width separate paths, so a cold update costs
// log2(n)·⌈width/8⌉ adjacent cache lines rather than width·log2(n) scattered ones. Each tree's
// minimum is the plain minimum of its leaves (the same value as a MinTree of them).
class MinTreeRows {
 public:
  static constexpr double kEmpty = MinTree::kEmpty;

  MinTreeRows(std::size_t leaves, std::size_t width)
      : size_(leaves > 0 ? leaves : 1), width_(width > 0 ? width : 1) {
    nodes_.assign(2 * size_ * width_, kEmpty);
  }

  std::size_t leaves() const { return size_; }
  std::size_t width() const { return width_; }
  double min(std::size_t tree) const { return nodes_[width_ + tree]; }
  double at(std::size_t i, std::size_t tree) const { return nodes_[(size_ + i) * width_ + tree]; }

  // Sets leaf i of tree j to values[j] for every j < width().
  void set(std::size_t i, const double* values) {
    std::size_t k = size_ + i;
    double* leaf = &nodes_[k * width_];
    for (std::size_t j = 0; j < width_; ++j) leaf[j] = values[j];
    propagate(k);
  }
  // Empties leaf i of every tree.
  void clear(std::size_t i) {
    std::size_t k = size_ + i;
    double* leaf = &nodes_[k * width_];
    for (std::size_t j = 0; j < width_; ++j) leaf[j] = kEmpty;
    propagate(k);
  }

 private:
  void propagate(std::size_t k) {
    for (k >>= 1; k != 0; k >>= 1) {
      double* node = &nodes_[k * width_];
      const double* a = &nodes_[2 * k * width_];
      const double* b = a + width_;
      bool changed = false;
      for (std::size_t j = 0; j < width_; ++j) {
        const double m = a[j] <= b[j] ? a[j] : b[j];
        changed = changed || node[j] != m;
        node[j] = m;
      }
      if (!changed) break;  // nothing above changes
    }
  }

  std::size_t size_, width_;
  std::vector<double> nodes_;
};

}  // namespace cncore::planner
