// The acceleration-limited type's caps (1.–3. in accel_limited.cpp): the pools of cap ids, their
// braking keys K = V² + 2·A0·σ(c) in the tournament trees, activation at the entry point and the
// feed caps' per-override-level keys (5.).
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited.hpp"
#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::MinTree;

void AccelLimitedAccDec::insert(std::size_t pos, const Cap& cap) {
  // (A cap the checks in on_segment() did not foresee, e.g. on_joint()'s lower cap for two
  // corners within one cycle, still holds the block when it binds at once.)
  if (!rekeying_ && !late_hold_ && late_check_ && late_cap(cap)) start_hold(late_at_mm_);
  if (late_hold_ && !rekeying_ && !releasing_) {
    pending_.emplace_back(pos, cap);  // takes effect when the hold ends (release_hold())
    return;
  }
  clear(pos);
  const std::size_t kind = pos % 3;
  const std::size_t g = free_[kind * pool_ + --free_n_[kind]];
  owner_[pos] = static_cast<std::uint32_t>(g);
  where_[g] = static_cast<std::uint32_t>(pos);
  caps_[g] = cap;
  const double entry = entry_mm(cap);
  caps_[g].entry = entry;
  if (pos_mm_ >= entry) {
    activate(g);
    return;
  }
  state_[g] = State::kApproaching;
  set_keys(g, entry);
}

void AccelLimitedAccDec::set_keys(std::size_t g, double entry) {
  const Cap& cap = caps_[g];
  entry_.set(g, entry);
  const double k_sigma = 2 * a0_ * cap.sigma_c;
  if (cap.lattice) {
    const double h = cap.v - 0.5 * a0_;
    key_lattice_.set(g, h * h + k_sigma);
  } else if (cap.feed) {
    feed_v_[g - pool_] = cap.v;
    feed_k_[g - pool_] = k_sigma;
    update_feed_group(g - pool_);
  } else {
    key_geo_.set(g, cap.v * cap.v + k_sigma);
  }
}

void AccelLimitedAccDec::move(std::size_t from, std::size_t to) {
  const std::uint32_t g = owner_[from];
  owner_[to] = g;
  owner_[from] = kNone;
  where_[g] = static_cast<std::uint32_t>(to);
}

double AccelLimitedAccDec::entry_mm(const Cap& cap) const {
  // A cap takes over where its key's bound has come down to V, σ(c) − σ(e) = V (3. (iii)).
  // A feed cap's V follows the override: it takes over at c. On an arc where 10. applies, and
  // where the search meets an event item, at c − V for a lattice key, else c (later, lower).
  const double late = cap.lattice ? cap.c_mm - cap.v : cap.c_mm;
  if (cap.feed) return late;
  std::size_t slot = 0;
  const double e = mm_at_sigma(cap.sigma_c - cap.v, cap.c_mm, slot);
  if (slot >= buf_.capacity() || arc_g_[slot] > 0) return late;
  return std::min(cap.c_mm - cap.v, e);
}

double AccelLimitedAccDec::mm_at_sigma(double target, double hint_mm, std::size_t& slot) const {
  // The lowest path position p (from the start of the tool's segment, or of the window's first)
  // with σ(p) ≥ target, for a target ≤ σ(hint_mm): back from hint_mm's item by galloping over
  // the items' σ at their starts, then bisection, then inside the segment's pieces. O(log n).
  // slot = capacity (none) where the items searched are not all motion items.
  slot = buf_.capacity();
  if (buf_.empty() || !have_prev_) return hint_mm;
  const std::uint64_t first = std::max(cur_, buf_.begin_index()), end = buf_.end_index();
  if (first >= end) return hint_mm;
  auto sigma0 = [&](std::uint64_t k) { return sigma0_[buf_.slot(k)]; };
  std::uint64_t hi = buf_.seek(first, hint_mm, UINT64_MAX, end - 1);
  if (!buf_.is_motion(hi)) return hint_mm;
  std::uint64_t lo = hi;
  if (sigma0(hi) > target) {
    // Invariant: σ0(hi) > target; then σ0(lo) ≤ target.
    for (std::uint64_t step = 1;; step *= 2) {
      const std::uint64_t probe = hi - std::min(step, hi - first);
      if (probe == hi || !buf_.is_motion(probe)) {
        // σ reaches the target before the first item searched: at its start (not the tool's
        // position: with the tool's item retired, the tool may still be before it).
        if (probe == hi) slot = buf_.slot(hi);
        return s0_mm_[buf_.slot(hi)];
      }
      if (sigma0(probe) <= target) {
        lo = probe;
        break;
      }
      hi = probe;
    }
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      if (!buf_.is_motion(mid)) return hint_mm;
      (sigma0(mid) <= target ? lo : hi) = mid;
    }
  }
  slot = buf_.slot(lo);
  const SigmaPieces& pc = pieces_[slot];
  const double t = target - sigma0_[slot];
  double x = 0;
  if (t > 0) {
    if (t <= pc.sig1 && pc.p1 > 0) {
      x = t / pc.rate0;
    } else if (t <= pc.sig2 && pc.p2 > pc.p1) {
      x = pc.p1 + (t - pc.sig1) / pc.rate1;
    } else {
      x = pc.p2 + (t - pc.sig2) / pc.rate2;
    }
    x = std::min(x, pc.len);
    // Rounding: σ(p) ≥ target exactly as seg_sigma() computes it.
    for (int it = 0; it < 4 && x < pc.len && seg_sigma(slot, x) < t; ++it) {
      x = std::nextafter(x, kInf);
    }
  }
  return s0_mm_[slot] + x;
}

void AccelLimitedAccDec::clear_keys(std::size_t g) {
  const Cap& cap = caps_[g];
  entry_.set(g, MinTree::kEmpty);
  if (cap.lattice) {
    key_lattice_.set(g, MinTree::kEmpty);
  } else if (cap.feed) {
    feed_k_[g - pool_] = kInf;
    update_feed_group(g - pool_);
  } else {
    key_geo_.set(g, MinTree::kEmpty);
  }
}

void AccelLimitedAccDec::update_feed_group(std::size_t i) {
  // The minima of the group of feed ids around i, level by level: the keys set_keys() gave
  // them, (j·step·V)² + 2·A0·σ(c), the same doubles (feed_key()).
  std::array<double, kMaxLevels> m;
  m.fill(kInf);
  const std::size_t lo = i / planner::MinTreeGroups::kFan * planner::MinTreeGroups::kFan;
  const std::size_t hi = std::min(pool_, lo + planner::MinTreeGroups::kFan);
  for (std::size_t k = lo; k < hi; ++k) {
    if (feed_k_[k] == kInf) continue;
    for (std::size_t j = 0; j < levels_; ++j) {
      const double key = feed_key(k, j);
      m[j] = key < m[j] ? key : m[j];
    }
  }
  key_feed_.set_group(i / planner::MinTreeGroups::kFan, m.data());
}

void AccelLimitedAccDec::activate(std::size_t g) {
  const Cap& cap = caps_[g];
  if (state_[g] == State::kApproaching) {
    clear_keys(g);
  }
  state_[g] = State::kActive;
  (cap.feed ? active_feed_ : active_geo_).set(g, cap.v);
  release_.set(g, cap.e_mm);
}

void AccelLimitedAccDec::clear(std::size_t pos) {
  const std::size_t g = owner_[pos];
  if (g == kNone) return;
  const bool feed = caps_[g].feed;
  if (state_[g] == State::kApproaching) {
    clear_keys(g);
  } else {
    (feed ? active_feed_ : active_geo_).set(g, MinTree::kEmpty);
    release_.set(g, MinTree::kEmpty);
  }
  state_[g] = State::kEmpty;
  owner_[pos] = kNone;
  where_[g] = kNone;
  const std::size_t kind = g / pool_;
  free_[kind * pool_ + free_n_[kind]++] = static_cast<std::uint32_t>(g);
}

}  // namespace cncore::motion
