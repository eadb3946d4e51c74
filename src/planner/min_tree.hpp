// A fixed-size tournament tree of doubles, 8 children per node: set one leaf in O(log n), read
// the minimum of all leaves in O(1), its index in O(log n) and the minimum over a range of
// leaves in O(log n). Memory is allocated once at construction; set/min/argmin/min_range never
// allocate. Empty leaves hold +infinity.
// Why 8-ary: a group of 8 siblings is one 64-byte cache line, so a leaf-to-root path is
// log8(n) lines (5 for 30 000 leaves) instead of log2(n) (15). argmin descends that path with
// one dependent load per level: on a cold tree (a cap activated after thousands of cycles
// without a touch) that is the cycle's latency. Ties go to the lowest index.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "planner/huge_pages.hpp"

namespace cncore::planner {

class MinTree {
 public:
  static constexpr double kEmpty = std::numeric_limits<double>::infinity();
  static constexpr std::size_t kFan = 8;

  explicit MinTree(std::size_t leaves) : size_(leaves > 0 ? leaves : 1) {
    // Levels from the leaves up to one root, each padded to whole groups of kFan.
    std::size_t count = size_, total = 0;
    for (;;) {
      const std::size_t padded = (count + kFan - 1) / kFan * kFan;
      offset_.push_back(total);
      total += padded;
      if (count == 1) break;
      count = (count + kFan - 1) / kFan;
    }
    // One spare line so that every group starts on a 64-byte boundary.
    storage_.assign(total + kFan, kEmpty);
    const auto addr = reinterpret_cast<std::uintptr_t>(storage_.data());
    const std::size_t skew = (64 - addr % 64) % 64 / sizeof(double);
    for (auto& o : offset_) o += skew;
    top_ = offset_.size() - 1;
    root_ = offset_[top_];
  }

  std::size_t leaves() const { return size_; }
  double at(std::size_t i) const { return storage_[offset_[0] + i]; }
  // A copy of the root's value kept in the object: read every cycle for several trees, whose
  // root lines the block pushes between two cycles would otherwise have evicted.
  double min() const { return min_; }

  void set(std::size_t i, double value) {
    storage_[offset_[0] + i] = value;
    for (std::size_t l = 0; l < top_; ++l) {
      const double* g = &storage_[offset_[l] + i / kFan * kFan];
      double m = g[0];
      for (std::size_t j = 1; j < kFan; ++j) m = g[j] < m ? g[j] : m;
      i /= kFan;
      double& parent = storage_[offset_[l + 1] + i];
      if (parent == m) break;  // nothing above changes
      parent = m;
    }
    min_ = storage_[root_];
  }

  // Index of a leaf holding min(), the lowest such (meaningless when the tree is empty).
  std::size_t argmin() const {
    std::size_t i = 0;
    for (std::size_t l = top_; l-- > 0;) {
      const double* g = &storage_[offset_[l] + i * kFan];
      std::size_t best = 0;
      for (std::size_t j = 1; j < kFan; ++j) best = g[j] < g[best] ? j : best;
      i = i * kFan + best;
    }
    return i;
  }

  // The minimum of leaves [lo, hi) (kEmpty when the range is empty).
  double min_range(std::size_t lo, std::size_t hi) const {
    double out = kEmpty;
    for (std::size_t l = 0; lo < hi; ++l) {
      const double* a = &storage_[offset_[l]];
      for (; lo < hi && lo % kFan != 0; ++lo) out = a[lo] < out ? a[lo] : out;
      while (lo < hi && hi % kFan != 0) {
        --hi;
        out = a[hi] < out ? a[hi] : out;
      }
      lo /= kFan;
      hi /= kFan;
    }
    return out;
  }

 private:
  double min_ = kEmpty;  // == storage_[root_]
  std::size_t size_;
  std::vector<std::size_t> offset_;                         // start of each level in storage_
  std::size_t top_ = 0;                                     // the root's level
  std::size_t root_ = 0;                                    // offset_[top_]: the root's slot
  std::vector<double, HugePageAllocator<double>> storage_;  // huge_pages.hpp: cheap to touch
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
  std::vector<double, HugePageAllocator<double>> nodes_;
};

// `width` tournament trees, 8-ary like MinTree, whose leaves the owner keeps (or computes from
// a few parameters per leaf): the lowest stored level holds, per group of kFan consecutive
// leaves, the minimum of each tree over that group, and the owner sets a group's minima after
// changing any of its leaves. For the acceleration-limited type's feed keys (21–41 override
// levels over ~10 000 caps) that is n/7 nodes of width doubles instead of MinTreeRows' 2·n:
// ~0.25 MB instead of 3.4 MB to allocate and touch at construction (on the VM we measure on a
// first touch costs ~30 µs per 4 KB or a 2 MB clear per huge page). Each tree's minimum is the
// plain minimum of the group minima given, so of the leaves.
class MinTreeGroups {
 public:
  static constexpr double kEmpty = MinTree::kEmpty;
  static constexpr std::size_t kFan = MinTree::kFan;

  MinTreeGroups(std::size_t leaves, std::size_t width)
      : groups_((std::max<std::size_t>(leaves, 1) + kFan - 1) / kFan),
        width_(width > 0 ? width : 1) {
    std::size_t count = groups_, total = 0;
    for (;;) {
      offset_.push_back(total);
      total += (count + kFan - 1) / kFan * kFan;
      if (count == 1) break;
      count = (count + kFan - 1) / kFan;
    }
    top_ = offset_.size() - 1;
    root_ = offset_[top_] * width_;
    nodes_.assign(total * width_, kEmpty);
  }

  std::size_t groups() const { return groups_; }
  std::size_t width() const { return width_; }
  double min(std::size_t tree) const { return nodes_[root_ + tree]; }
  // The minima of group k as last set (kEmpty for a group never set).
  double group_min(std::size_t k, std::size_t tree) const {
    return nodes_[(offset_[0] + k) * width_ + tree];
  }

  // Sets the minima of the leaves kFan·k … kFan·k + kFan − 1, one per tree (minima[j] for tree
  // j < width()), and the nodes above them.
  void set_group(std::size_t k, const double* minima) {
    double* node = &nodes_[(offset_[0] + k) * width_];
    for (std::size_t j = 0; j < width_; ++j) node[j] = minima[j];
    for (std::size_t l = 0; l < top_; ++l) {
      const double* g = &nodes_[(offset_[l] + k / kFan * kFan) * width_];
      k /= kFan;
      double* parent = &nodes_[(offset_[l + 1] + k) * width_];
      bool changed = false;
      for (std::size_t j = 0; j < width_; ++j) {
        double m = g[j];
        for (std::size_t c = 1; c < kFan; ++c) {
          const double x = g[c * width_ + j];
          m = x < m ? x : m;
        }
        changed = changed || parent[j] != m;
        parent[j] = m;
      }
      if (!changed) break;  // nothing above changes
    }
  }

 private:
  std::size_t groups_, width_;
  std::vector<std::size_t> offset_;  // first node of each level (in nodes)
  std::size_t top_ = 0;
  std::size_t root_ = 0;  // index of the root's first value
  std::vector<double, HugePageAllocator<double>> nodes_;
};

}  // namespace cncore::planner
