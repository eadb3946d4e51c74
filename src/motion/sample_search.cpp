// The sample search: see sample_search.hpp for what it does, docs/lookahead.md for why, and
// bench/bound/sampled_reference.cpp (cncore-sref) for the whole-program version whose figures
// this one reproduces with fixed buffers.
//
// This file: construction, the window of segments and the effective caps of the backward guide.
// The rules of a step are in sample_search_rules.cpp, the beam, its commits and the cycle in
// sample_search_beam.cpp.
#include "motion/sample_search.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "motion/sample_search_common.hpp"

namespace cncore::motion {

using namespace sample_search_common;  // NOLINT(google-build-using-namespace)

SampleSearch::SampleSearch(const planner::Limits& limits, const SampleSearchOptions& options)
    : lim_(limits), opt_(options) {
  const double m = opt_.limit_factor;
  a_ = m * lim_.amax_pc2;
  normal_ = a_;
  resultant_ = lim_.bound_resultant ? a_ : 0.0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i]) continue;
    if (lim_.axis_amax_pc2[i] > 0) axis_a_[i] = m * lim_.axis_amax_pc2[i];
    if (lim_.axis_vmax_pc[i] > 0) axis_v_[i] = m * lim_.axis_vmax_pc[i];
  }
  max_step_ = m * std::max(lim_.vmax_pc, lim_.rapid_pc);
  // The front stays this far before a window end that is not the program's: there the guide
  // never sees the window's temporary stop, and neither does the brake of a committed state.
  reach_mm_ = brake_distance(max_step_, 0) + 2 * max_step_;
  eff_horizon_mm_ = reach_mm_;
  bin_w_ = a_ / opt_.bins_per_a;
  nbins_ = static_cast<std::size_t>(max_step_ / bin_w_) + 2;
  beam_cap_ = kClasses * nbins_ * opt_.per_bin;
  hist_rows_ = opt_.max_lag_cycles + 2 * kCoalesceEvery;
  cand_cap_ = opt_.grid + 1 + 4 * opt_.joints_per_step;
  // The brake from a state at the top speed takes max_step/a cycles plus a few at the caps.
  const auto brake_cycles = static_cast<std::size_t>(max_step_ / a_) + 64;
  const std::size_t out_cap = std::max(opt_.output_cycles, 2 * (hist_rows_ + brake_cycles));

  // A power of two, so that a segment's slot is a mask, not a division (it was ~10 % of the
  // search, in every rule that walks the joints); the window holds window_segments of them.
  segs_.resize(std::bit_ceil(std::max<std::size_t>(opt_.window_segments, 1)));
  seg_mask_ = segs_.size() - 1;
  beam_.reserve(beam_cap_);
  bins_.resize(beam_cap_);
  bin_n_.assign(kClasses * nbins_, 0);
  cand_s_.resize(cand_cap_);
  cands_.resize(5 * cand_cap_);  // the base ones, and two boundaries per pair and direction
  hist_.resize(hist_rows_ * beam_cap_);
  mark_.assign(beam_cap_, 0);
  idx_a_.resize(beam_cap_);
  idx_b_.resize(beam_cap_);
  trace_.resize(hist_rows_ + 1);
  out_.resize(out_cap);
  hard_q_.resize(opt_.window_segments);
  out_reserve_ = hist_rows_ + brake_cycles;
}

bool SampleSearch::wants_segment() const {
  return seg_end_ - seg_base_ < opt_.window_segments && !program_ended_;
}

bool SampleSearch::push(const planner::Segment& segment, bool stop_after) {
  if (!wants_segment() || segment.kind != planner::ItemKind::kMotion || segment.length_mm <= 0)
    return false;
  const Vec3 chord = segment.end.xyz() - segment.start.xyz();
  if (!segment.arc && norm(chord) <= 0) return false;  // rotary-only: not supported
  if (seg_end_ > 0 && std::abs(segment.s0_mm - joint_s(seg_end_ - 1)) > 1e-9) return false;
  const std::uint64_t idx = seg_end_;
  Seg& g = seg(idx);
  g.geo = segment;
  const double m = opt_.limit_factor;
  g.shape = m * shape_cap(segment);
  g.feed = segment.feed_pc > 0 ? m * segment.feed_pc : kInf;
  g.joint_cap = a_;  // the window's end: a stop until the next segment arrives
  g.stop = true;
  g.hard_stop = false;
  g.turn_cos = 1;
  const bool fresh = eff_fresh_ >= seg_end_;
  ++seg_end_;
  if (idx > 0 && !seg(idx - 1).hard_stop) join(idx - 1);
  update_eff(idx);
  if (fresh) eff_fresh_ = seg_end_;
  if (stop_after) mark_stop();
  if (idx == 0) {
    // The tool rests at the first segment's start: cycle 0.
    const double s0 = segment.s0_mm;
    beam_.assign(1, Node{s0, s0, 0, 0});
    hist(0, 0) = {s0, -1};
    last_commit_ = beam_[0];
    popped_s_ = popped_sp_ = s0;
    emit(beam_[0], 0);
  }
  return true;
}

void SampleSearch::join(std::uint64_t j) {
  Seg& a = seg(j);
  const Seg& b = seg(j + 1);
  a.joint_cap = opt_.limit_factor * corner_cap(a.geo, b.geo);
  const Vec3 e = a.geo.end_direction().xyz(), s = b.geo.start_direction().xyz();
  const double ne = norm(e), ns = norm(s);
  a.turn_cos = ne > 0 && ns > 0 ? dot(e, s) / (ne * ns) : 1.0;
  a.stop = false;
}

// The checker's speed limit of a segment's shape: the feed or rapid rate, and √(R·Amax) on an
// arc (R the smaller radius of a spiral). The planner's Vb is lower: it keeps room for the moving
// average's ramp and the per-axis limits, which the search checks on the samples themselves.
double SampleSearch::shape_cap(const planner::Segment& s) const {
  double v = s.rapid ? lim_.rapid_pc : lim_.vmax_pc;
  if (s.arc) v = std::min(v, std::sqrt(std::min(s.r0, s.r1) * lim_.amax_pc2));
  return v;
}

// The checker's passing speed of a joint: both shapes' limits and the turn within one cycle,
// Vg = Amax·τ/(2 sin(θ/2)) = Amax·τ/|S − E| with S, E the unit tangents.
double SampleSearch::corner_cap(const planner::Segment& a, const planner::Segment& b) const {
  const Vec3 e = a.end_direction().xyz(), s = b.start_direction().xyz();
  const double ne = norm(e), ns = norm(s);
  double v = std::min(shape_cap(a), shape_cap(b));
  if (ne > 0 && ns > 0) {
    const double turn = norm((1.0 / ns) * s - (1.0 / ne) * e);
    if (turn > 1e-12) v = std::min(v, lim_.amax_pc2 / turn);
  }
  return v;
}

bool SampleSearch::push(const Block& block) {
  if (block.kind == BlockKind::kDwell) return false;
  if (block.kind == BlockKind::kAux) {
    if (block.aux_waits) mark_stop();
    return true;
  }
  if (!wants_segment()) return false;
  planner::Segment s = planner::make_motion_segment(block, lim_);
  if (s.length_mm <= 0) return true;
  s.s0_mm = seg_end_ > 0 ? joint_s(seg_end_ - 1) : 0.0;
  return push(s, block.path_mode == PathMode::kExactStop);
}

void SampleSearch::end_of_program() {
  program_ended_ = true;
}

// Shortest distance from a sample reached with step d to the last sample before a joint that
// must be crossed with a step ≤ c, the steps shrinking by a per cycle at most: the landings of
// d − a, d − 2a, …, while they are above c:
//   Σ_{i=1}^{m−1} (d − i·a) = (m−1)·d − a·m·(m−1)/2,  m = ⌈(d − c)/a⌉.
double SampleSearch::brake_distance(double d, double c) const {
  // Up to kRound, as the rules: d = c + a exactly (the cap's step plus a) read d − a > c by ulps
  // and cost a braking step the rules do not ask for.
  if (d - a_ <= c + kRound) return 0;
  const double m1 = std::ceil((d - c - kRound) / a_) - 1;
  return m1 * d - a_ * m1 * (m1 + 1) / 2;
}

// The largest step d with brake_distance(d, c) < room (room > 0). With c' = c + kRound the
// distance is 0 up to d = c' + a and, for d − c' in (k·a, (k+1)·a], k·d − a·k·(k+1)/2: rising
// in d, with a jump of c' where k steps up. Its value at the top of interval k is
// k·c' + a·k·(k+1)/2; the first k where that reaches room, from (a/2)·k² + (c' + a/2)·k = room,
// holds the answer: d < (room + a·k·(k+1)/2)/k there, and never below the interval's foot
// c' + k·a (the jump). The closed form then moves by ulps to the largest double below the
// bound (a bisection would take 60 steps per joint, walked back over the braking distance each
// time a segment arrives: most of the search's time on a window of 10 000 short segments).
double SampleSearch::brake_limit(double c, double room) const {
  const double c1 = c + kRound;
  const double b = c1 + a_ / 2;
  double k = std::max(1.0, std::ceil((std::sqrt(b * b + 2 * a_ * room) - b) / a_));
  while (k > 1 && (k - 1) * c1 + a_ * (k - 1) * k / 2 >= room) --k;
  while (k * c1 + a_ * k * (k + 1) / 2 < room) ++k;
  double d = std::max(c1 + k * a_, (room + a_ * k * (k + 1) / 2) / k);
  while (d > 0 && brake_distance(d, c) >= room) d = std::nextafter(d, 0.0);
  for (double up = std::nextafter(d, kInf); brake_distance(up, c) < room;
       up = std::nextafter(d, kInf))
    d = up;
  return d;
}

// The effective cap of joint j for the backward guide: a crossing step of joint j touches
// segment j, so it is below that segment's cap too, and after crossing j, joint j+1 must still
// be met (the largest d with brake_distance(d, eff_{j+1}) < room). Reads eff_{j+1}.
double SampleSearch::eff_of(std::uint64_t j) const {
  // A stop must be landed on exactly: the step after it is 0, so braking counts down to 0
  // there (with the cap a instead, a state at 1.9·a a few µm before the end passed the guide
  // and could only land by slowing to rest short of it and creeping on).
  const Seg& g = seg(j);
  if (g.stop) return 0.0;
  double eff = std::min(g.joint_cap, cap(g, or_));
  if (j + 1 < seg_end_) {
    // Landing on joint j with step x, the next step (inside segment j+1) is ≥ x − a: so x ≤
    // cap_{j+1} + a as well.
    eff = std::min(eff, cap(seg(j + 1), or_) + a_);
    const double next = seg(j + 1).eff;
    const double room = joint_s(j + 1) - joint_s(j);
    if (brake_distance(eff, next) >= room) eff = brake_limit(next, room);
  }
  return eff;
}

// A segment arrived: from the last one back while the effective caps change.
void SampleSearch::update_eff(std::uint64_t last) {
  seg(last).eff = eff_of(last);
  for (std::uint64_t j = last; j-- > seg_base_;) {
    const double eff = eff_of(j);
    if (eff == seg(j).eff && j + 1 < last) break;
    seg(j).eff = eff;
  }
}

// The override changed (restart()): every effective cap may change, but the guide reads only
// those within a braking distance of the front. The caps are made current up to `upto_mm` (a
// joint's cap depends only on the caps within eff_horizon_mm_ of it: a braking
// distance from the top speed and two steps), from a pass that starts twice that far ahead on the
// older caps, so a change of override costs one pass over ~3 horizons, not over the window
// (~30 ns a segment: 0.3 ms on a window of 10 000 segments, in the cycle of the change).
void SampleSearch::refresh_eff(double upto_mm) {
  eff_fresh_ = std::max(eff_fresh_, seg_base_);
  if (eff_fresh_ >= seg_end_ || joint_s(eff_fresh_) > upto_mm) return;
  const double h = eff_horizon_mm_;
  std::uint64_t last = eff_fresh_;
  while (last + 1 < seg_end_ && joint_s(last) < upto_mm + 2 * h) ++last;
  const bool to_end = last + 1 == seg_end_;
  if (to_end) seg(last).eff = eff_of(last);
  for (std::uint64_t j = last; j-- > eff_fresh_;) seg(j).eff = eff_of(j);
  if (to_end) {
    eff_fresh_ = seg_end_;
    return;
  }
  while (eff_fresh_ < last && joint_s(eff_fresh_) < joint_s(last) - h) ++eff_fresh_;
}

std::uint64_t SampleSearch::seg_of(double s, std::uint64_t hint) const {
  std::uint64_t j = std::clamp(hint, seg_base_, seg_end_ - 1);
  while (j + 1 < seg_end_ && s >= seg(j + 1).geo.s0_mm) ++j;
  while (j > seg_base_ && s < seg(j).geo.s0_mm) --j;
  return j;
}

AxisVec SampleSearch::point(double s, std::uint64_t segment) const {
  const planner::Segment& g = seg(segment).geo;
  return g.point_at(s - g.s0_mm);
}

}  // namespace cncore::motion
