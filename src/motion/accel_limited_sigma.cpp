// The acceleration-limited type's path coordinate σ(s) = ∫ r ds (2. in accel_limited.cpp): the
// acceleration ratio r per segment with its joint zones' heads and tails, σ by pieces, the lowest
// r over a span (r_span()), and σ recomputed after a zone changes it.
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited.hpp"
#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::ItemKind;
using planner::MinTree;
using planner::Segment;

void AccelLimitedAccDec::update_r(std::uint64_t index) {
  const Segment& s = buf_[index];
  const std::size_t slot = buf_.slot(index);
  if (s.kind != ItemKind::kMotion) {
    r_zone_.set(slot, MinTree::kEmpty);
    return;
  }
  // r_span()'s rate of a segment inside [from, to] as a whole (from ≤ s0, end ≤ to), written
  // as there so that the minimum is the same bit for bit.
  double rate = ratio_[slot];
  if (0.0 < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
  if (s.end_mm() - s.s0_mm > s.length_mm - tail_mm_[slot]) rate = std::min(rate, tail_r_[slot]);
  // (A slot usually holds 1 already: on_retire() leaves leaves of 1.)
  if (r_zone_.at(slot) != rate) r_zone_.set(slot, rate);
}

void AccelLimitedAccDec::add_head(std::size_t slot, double mm, double r, double r_dec) {
  if (mm <= 0 || r >= 1) return;
  head_r_[slot] = head_mm_[slot] > 0 ? std::min(head_r_[slot], r) : r;
  head_rd_[slot] = head_mm_[slot] > 0 ? std::min(head_rd_[slot], r_dec) : r_dec;
  head_mm_[slot] = std::max(head_mm_[slot], mm);
  refresh_pieces(slot);
}

void AccelLimitedAccDec::carry(double until_mm, double r) {
  if (n_carries_ == kCarries) {
    // Full: merge the two that end first (the lower r over the longer reach: stricter).
    std::sort(carries_.begin(), carries_.end(),
              [](const Carry& x, const Carry& y) { return x.until_mm < y.until_mm; });
    carries_[1] = {carries_[1].until_mm, std::min(carries_[0].r, carries_[1].r)};
    carries_[0] = carries_[--n_carries_];
  }
  carries_[n_carries_++] = {until_mm, r};
}

void AccelLimitedAccDec::advance_current() {
  if (buf_.empty()) return;
  cur_ = std::max(cur_, buf_.begin_index());
  // Skip the segments the tool has passed by a galloping search over the buffer's end
  // positions (many tiny segments per cycle); the walk below then only steps over events.
  auto passed = [&] {
    return cur_ + 1 < buf_.end_index() &&
           (buf_[cur_].kind != ItemKind::kMotion || pos_mm_ >= buf_[cur_].end_mm());
  };
  if (!passed()) return;  // the usual cycle: still inside the same segment
  // Hint: as many items as the last cycle that left its item skipped (fine segments of even
  // length at an even speed: a probe or two).
  const std::uint64_t from = cur_;
  cur_ = buf_.seek(cur_, pos_mm_, UINT64_MAX, cur_ + cur_skip_);
  while (passed()) ++cur_;
  cur_skip_ = cur_ - from;
}

double AccelLimitedAccDec::sigma_at(double pos_mm) const {
  if (!have_prev_ || pos_mm >= prev_end_mm_ || buf_.empty()) return sigma_total_;
  // The last item starting at or before pos_mm (items are in path order), then back to a
  // motion item: O(log n), only when the stop position changes.
  const std::uint64_t first = std::max(cur_, buf_.begin_index());
  std::uint64_t lo = first, hi = buf_.end_index();
  if (lo >= hi) return sigma_total_;
  // s0 of item k is the end of item k − 1, read from the buffer's compact array: a probe of 8
  // bytes instead of a cold ~330-byte Segment. Galloping back from the window's end first (the
  // caps of a new block, and their zones, ask for positions near it), then bisection:
  // invariant s0(hi) > pos (or hi the end), and lo = first or s0(lo) ≤ pos.
  for (std::uint64_t step = 1; hi - first > step; step *= 2) {
    const std::uint64_t probe = hi - step;
    if (buf_.end_mm_of(probe - 1) <= pos_mm) {
      lo = probe;
      break;
    }
    hi = probe;
  }
  while (hi - lo > 1) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    if (buf_.end_mm_of(mid - 1) <= pos_mm) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  std::uint64_t i = lo;
  while (i > buf_.begin_index() && buf_[i].kind != ItemKind::kMotion) --i;
  const Segment& s = buf_[i];
  if (s.kind != ItemKind::kMotion) return sigma_total_;
  const std::size_t slot = buf_.slot(i);
  return sigma0_[slot] + seg_sigma(slot, pos_mm - s.s0_mm);
}

void AccelLimitedAccDec::refresh_pieces(std::size_t slot) {
  // Pieces [0, h), [h, L − t), [L − t, L] (overlapping zones: the lower r of both). σ at the
  // piece ends is summed in the order seg_sigma() adds the pieces, so both give the same double
  // as summing the pieces up to x one by one (0 + y = y; an empty piece adds r·0 = 0).
  const double len = len_mm_[slot];
  const double r = ratio_[slot];
  const double h = std::min(head_mm_[slot], len);
  const double t0 = std::max(0.0, len - tail_mm_[slot]);
  const double pts[4] = {0, std::min(h, t0), std::max(h, t0), len};
  double rate[3];
  for (std::size_t k = 0; k < 3; ++k) {
    const double mid = 0.5 * (pts[k] + pts[k + 1]);
    rate[k] = r;
    if (mid < h) rate[k] = std::min(rate[k], head_rd_[slot]);
    if (mid > t0) rate[k] = std::min(rate[k], tail_rd_[slot]);
  }
  SigmaPieces& p = pieces_[slot];
  p.len = len;
  p.p1 = pts[1];
  p.p2 = pts[2];
  p.rate0 = rate[0];
  p.rate1 = rate[1];
  p.rate2 = rate[2];
  p.sig1 = pts[1] > 0 ? rate[0] * pts[1] : 0.0;
  p.sig2 = pts[2] > pts[1] ? p.sig1 + rate[1] * (pts[2] - pts[1]) : p.sig1;
}

double AccelLimitedAccDec::seg_sigma(std::size_t slot, double x_mm) const {
  const SigmaPieces& p = pieces_[slot];
  const double x = std::clamp(x_mm, 0.0, p.len);
  if (x <= p.p1) return x > 0 ? p.rate0 * x : 0.0;
  if (x <= p.p2) return p.sig1 + p.rate1 * (x - p.p1);
  return p.sig2 + p.rate2 * (x - p.p2);
}

double AccelLimitedAccDec::r_span(double from_mm, double to_mm, std::uint64_t* skip) const {
  double out = 1;
  if (buf_.empty()) return out;
  const std::uint64_t first = std::max(cur_, buf_.begin_index()), end = buf_.end_index();
  if (first >= end) return out;
  // One item of the walk "motion items from `first` while s0 ≤ to"; false: stop. From the
  // compact per-slot arrays (the same doubles as the Segment's): the pushes between two cycles
  // of fine segments evict the cold Segments the walk would otherwise load.
  auto item = [&](std::uint64_t k) {
    if (!buf_.is_motion(k)) return true;
    const std::size_t slot = buf_.slot(k);
    const double s0 = s0_mm_[slot];
    if (s0 > to_mm) return false;
    const double e = buf_.end_mm_of(k);
    if (e < from_mm) return true;
    double rate = ratio_[slot];
    if (std::max(from_mm, s0) - s0 < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
    if (std::min(to_mm, e) - s0 > len_mm_[slot] - tail_mm_[slot]) {
      rate = std::min(rate, tail_r_[slot]);
    }
    out = std::min(out, rate);
    return true;
  };
  // An item's rate over any part of it lies between its rate as a whole (its leaf of r_zone_,
  // kept current by update_r(); events and retired slots: ≥ 1) and 1. So where no leaf of the
  // items the walk may visit is below 1, the minimum is exactly 1 (the usual case between
  // joint zones): read from the compact leaves, not from the items.
  const std::size_t cap = buf_.capacity();
  auto range_min = [&](const MinTree& t, std::size_t a, std::size_t n) {
    return a + n <= cap ? t.min_range(a, a + n)
                        : std::min(t.min_range(a, cap), t.min_range(0, a + n - cap));
  };
  // The usual cycle: the step stays inside the tool's segment.
  const bool f_motion = buf_.is_motion(first);
  const double f_end = buf_.end_mm_of(first);
  if (f_motion && to_mm < f_end) {
    if (r_zone_.at(buf_.slot(first)) >= 1) return out;
    item(first);
    return out;
  }
  // The walk ends at or before `last`, the item containing to_mm (items after it start past
  // to_mm). Short spans: walked.
  // (Hint: the skip of the last call for the same kind of span, when the caller keeps one.)
  const std::uint64_t last =
      buf_.seek(first, to_mm, UINT64_MAX, skip != nullptr ? first + *skip : 0);
  if (skip != nullptr) *skip = last - first;
  // The leaves of first and last, and the minimum of those between (used again below).
  const double inner = last > first + 1 ? range_min(r_zone_, buf_.slot(first + 1),
                                                    static_cast<std::size_t>(last - first - 1))
                                        : MinTree::kEmpty;
  if (std::min(std::min(r_zone_.at(buf_.slot(first)), inner), r_zone_.at(buf_.slot(last))) >= 1) {
    return out;
  }
  if (last - first <= 8 || !f_motion || !(f_end > from_mm)) {
    for (std::uint64_t k = first; k <= last && item(k); ++k) {
    }
    return out;
  }
  // Long spans (many tiny segments per step): the first item (the tool's, ending after from_mm)
  // and the last one as in the walk; every item between starts after from_mm and ends at or
  // before to_mm (seek() skipped it), so its rate is that of the whole item: a range minimum.
  if (!item(first)) return out;
  out = std::min(out, inner);
  item(last);
  return out;
}

void AccelLimitedAccDec::resigma(std::uint64_t first, std::uint64_t index_a) {
  const Segment& a = buf_[index_a];
  const std::size_t sa = buf_.slot(index_a);
  // σ after the first changed segment moved: the starts of the later ones, the end of the
  // window, the cached σ of the stop, and the keys of the caps from there on (exact σ(c)).
  for (std::uint64_t k = first; k < index_a; ++k) {
    if (buf_[k].kind != ItemKind::kMotion) continue;
    const std::size_t sk = buf_.slot(k);
    double next = sigma0_[sk] + seg_sigma(sk, len_mm_[sk]);
    for (std::uint64_t n = k + 1; n <= index_a; ++n) {
      if (buf_[n].kind != ItemKind::kMotion) continue;
      sigma0_[buf_.slot(n)] = next;
      break;
    }
  }
  sigma_total_ = sigma0_[sa] + seg_sigma(sa, a.length_mm);
  cached_stop_mm_ = -1;
  const double from_mm = buf_[first].s0_mm;
  for (std::uint64_t k = first; k <= index_a; ++k) {
    if (buf_[k].kind != ItemKind::kMotion) continue;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t cs = 3 * buf_.slot(k) + c;
      if (pos_state(cs) != State::kApproaching || caps_[owner_[cs]].c_mm < from_mm) continue;
      const std::size_t g = owner_[cs];
      Cap cap = caps_[g];
      cap.sigma_c = sigma_at(cap.c_mm);
      if (c == 2 && cap.v < a0_) {
        cap.lattice = cap.v >= 0.5 * a0_ && cap.sigma_c - sigma_at(cap.c_mm - cap.v) >= 0.5 * cap.v;
      }
      // Unchanged and still ahead of the tool: nothing to do (insert() would set the same keys).
      if (cap.sigma_c == caps_[g].sigma_c && cap.lattice == caps_[g].lattice &&
          pos_mm_ < entry_mm(cap)) {
        continue;
      }
      rekeying_ = true;  // (a live cap's key follows the σ already changed above)
      insert(cs, cap);
      rekeying_ = false;
    }
  }
}

}  // namespace cncore::motion
