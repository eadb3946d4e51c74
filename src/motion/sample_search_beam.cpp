// The sample search's beam and cycle: keeping the K farthest states per speed bin, committing
// lineages, certifying and handing out committed samples, recovery, override restarts, and
// advance(), the search's share of one cycle.
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/sample_search.hpp"
#include "motion/sample_search_common.hpp"

namespace cncore::motion {

using namespace sample_search_common;  // NOLINT(google-build-using-namespace)

// Keeps a child if it is among the K farthest of its speed bin (ties: the smaller previous
// sample), dropping exact duplicates.
void SampleSearch::offer(const Node& c, std::size_t cls) {
  const std::size_t b =
      cls * nbins_ + std::min(nbins_ - 1, static_cast<std::size_t>((c.s - c.sp) / bin_w_));
  Node* bin = &bins_[b * opt_.per_bin];
  std::size_t& nb = bin_n_[b];
  auto better = [](const Node& x, const Node& y) { return x.s != y.s ? x.s > y.s : x.sp < y.sp; };
  for (std::size_t i = 0; i < nb; ++i)
    if (std::abs(bin[i].s - c.s) < 1e-12 && std::abs(bin[i].sp - c.sp) < 1e-12) return;
  std::size_t pos = nb;
  while (pos > 0 && better(c, bin[pos - 1])) --pos;
  if (pos >= opt_.per_bin) return;
  const std::size_t last = std::min(nb, opt_.per_bin - 1);
  for (std::size_t i = last; i > pos; --i) bin[i] = bin[i - 1];
  bin[pos] = c;
  nb = std::min(nb + 1, opt_.per_bin);
}

void SampleSearch::emit(const Node& n, std::uint64_t cycle, bool pending) {
  // A sample on a joint belongs to the segment it arrived by (its block's line).
  std::uint64_t line_seg = n.seg;
  if (line_seg > seg_base_ && n.s == seg(line_seg).geo.s0_mm) --line_seg;
  Out& o = out_[(out_head_ + out_count_) % out_.size()];
  o = {point(n.s, n.seg), seg(line_seg).geo.line, n.s, pending, n.sp, n.seg, cycle};
  ++out_count_;
}

// The newest popped sample (the tool's) becomes the newest committed state.
void SampleSearch::from_tool() {
  committed_ = popped_n_ > 0 ? popped_n_ - 1 : 0;
  last_commit_ = Node{popped_sp_, popped_s_, seg_of(popped_s_, last_commit_.seg), -1};
}

bool SampleSearch::pop(AxisVec& position, std::uint32_t& line, double& s_mm) {
  if (out_count_ == 0) return false;
  if (out_[out_head_].pending) {
    // Certified as it is handed out, not when its lineage is committed: one brake per cycle
    // instead of up to L in the cycle a lineage coalesces (the search's worst cycles).
    const Out& o = out_[out_head_];
    const std::size_t k = brake_to_rest(Node{o.sp, o.s, o.seg, -1}, o.cycle, false);
    if (k == 0) {
      // Met like a death, from the tool's sample (certified when it was popped): what was
      // planned after it goes.
      ++stats_.uncertified;
      out_count_ = 0;
      from_tool();
      at_stop_ = finished_ = false;
      recover();
      if (out_count_ == 0) return false;
    } else {
      stats_.longest_brake = std::max(stats_.longest_brake, k);
      out_[out_head_].pending = false;
    }
  }
  const Out& o = out_[out_head_];
  position = o.p;
  line = o.line;
  s_mm = o.s;
  popped_sp_ = popped_n_ > 0 ? popped_s_ : o.s;
  popped_s_ = o.s;
  ++popped_n_;
  out_head_ = (out_head_ + 1) % out_.size();
  --out_count_;
  return true;
}

// Commits the state n (the cycle after committed_); pop() certifies it (its greedy brake to
// rest) before handing it out.
void SampleSearch::commit_pending(const Node& n) {
  ++committed_;
  last_commit_ = n;
  emit(n, committed_, true);
}

// The lineage of entry i of row `cycle`, from committed_ + 1 up to `cycle`, is committed state
// by state (pop() certifies each before handing it out).
void SampleSearch::commit_lineage(std::uint64_t cycle, std::size_t i) {
  const auto len = static_cast<std::size_t>(cycle - committed_);
  for (std::size_t k = len; k-- > 0;) {
    const Hist& h = hist(committed_ + 1 + k, i);
    trace_[k] = Node{0, h.s, 0, static_cast<std::int32_t>(i)};
    i = static_cast<std::size_t>(h.parent);
  }
  for (std::size_t k = 0; k < len; ++k) {
    Node n{last_commit_.s, trace_[k].s, 0, -1};
    n.seg = seg_of(n.s, last_commit_.seg);
    commit_pending(n);
  }
  retire();
}

void SampleSearch::retire() {
  // Behind the tool (the newest popped sample): a restart starts from there.
  const double behind = std::min(last_commit_.sp, popped_sp_);
  while (seg_base_ + 1 < seg_end_ && seg(seg_base_).geo.end_mm() < behind) ++seg_base_;
}

// The newest cycle from which every live state descends, by walking the live states' ancestors
// back one row at a time (distinct indices marked with a stamp).
void SampleSearch::find_coalescence() {
  std::size_t n = beam_.size();
  for (std::size_t i = 0; i < n; ++i) idx_a_[i] = static_cast<std::uint32_t>(i);
  for (std::uint64_t c = front_; c > committed_; --c) {
    if (n == 1) {
      commit_lineage(c, idx_a_[0]);
      return;
    }
    ++stamp_;
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto p = static_cast<std::uint32_t>(hist(c, idx_a_[i]).parent);
      if (mark_[p] == stamp_) continue;
      mark_[p] = stamp_;
      idx_b_[m++] = p;
    }
    std::swap(idx_a_, idx_b_);
    n = m;
  }
}

std::size_t SampleSearch::ancestor(std::size_t i, std::uint64_t cycle) const {
  for (std::uint64_t c = front_; c > cycle; --c) i = static_cast<std::size_t>(hist(c, i).parent);
  return i;
}

// The commits lag the front by more than L: keep only the states that share, L/2 cycles back,
// the ancestor of the farthest state whose ancestor there brakes to rest.
void SampleSearch::force_commit() {
  ++stats_.forced;
  const std::uint64_t c0 = front_ - opt_.max_lag_cycles / 2;
  const std::size_t n = beam_.size();
  for (std::size_t i = 0; i < n; ++i) idx_a_[i] = static_cast<std::uint32_t>(i);
  std::sort(idx_a_.begin(), idx_a_.begin() + static_cast<std::ptrdiff_t>(n),
            [&](std::uint32_t x, std::uint32_t y) { return beam_[x].s > beam_[y].s; });
  std::size_t target = beam_cap_;
  for (std::size_t k = 0; k < n && target == beam_cap_; ++k) {
    const std::size_t t = ancestor(idx_a_[k], c0);
    const Hist& h = hist(c0, t);
    const double sp = hist(c0 - 1, static_cast<std::size_t>(h.parent)).s;
    const Node st{sp, h.s, seg_of(h.s, last_commit_.seg), -1};
    if (brake_to_rest(st, c0, false) > 0) target = t;
  }
  if (target == beam_cap_) {
    recover();
    return;
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (ancestor(i, c0) != target) continue;
    hist(front_, kept) = hist(front_, i);
    beam_[kept] = beam_[i];
    beam_[kept].parent = static_cast<std::int32_t>(kept);
    ++kept;
  }
  beam_.resize(kept);
  find_coalescence();
}

// The beam died, a forced commit found no lineage that brakes to rest, or a hold: the tool
// brakes to rest from the newest committed state that certifies, and the search starts again
// from rest.
void SampleSearch::recover() {
  ++stats_.recoveries;
  // The newest committed state may not be certified yet (pop() certifies): the newest that is
  // brakes, and what was committed after it goes (pop() still certifies those before it).
  while (out_count_ > 0) {
    Out& o = out_[(out_head_ + out_count_ - 1) % out_.size()];
    if (!o.pending) break;
    if (brake_to_rest(Node{o.sp, o.s, o.seg, -1}, o.cycle, false) > 0) {
      o.pending = false;
      break;
    }
    ++stats_.uncertified;
    if (--out_count_ == 0) {
      from_tool();
    } else {
      const Out& b = out_[(out_head_ + out_count_ - 1) % out_.size()];
      committed_ = b.cycle;
      last_commit_ = Node{b.sp, b.s, b.seg, -1};
    }
  }
  if (brake_to_rest(last_commit_, committed_, true) == 0) {
    failed_ = true;  // cannot happen: the state was certified by this very brake
    return;
  }
  front_ = committed_;
  if (last_commit_.s == terminal()) {
    reached_terminal();
    return;
  }
  restart_at_rest();
}

void SampleSearch::restart_at_rest() {
  const double s = last_commit_.s;
  last_commit_.sp = s;
  beam_.assign(1, Node{s, s, last_commit_.seg, 0});
  hist(front_, 0) = {s, -1};
  retire();
}

double SampleSearch::terminal() const {
  if (hard_n_ > 0) return joint_s(hard_q_[hard_head_]);
  return program_ended_ && seg_end_ > 0 ? joint_s(seg_end_ - 1) : kInf;
}

void SampleSearch::reached_terminal() {
  if (program_ended_ && last_commit_.s == joint_s(seg_end_ - 1)) {
    finished_ = true;
    return;
  }
  // One sample at rest on the stop: the tool has stopped there (the kernel handles the event
  // then), and the plan after it starts from rest, not from the landing step.
  at_stop_ = true;
  last_commit_.sp = last_commit_.s;
  emit(last_commit_, committed_ + 1);
  front_ = ++committed_;
}

void SampleSearch::mark_stop() {
  if (seg_end_ == 0) {
    stop_at_start_ = true;  // a stop before any motion: wait at the start for resume()
    return;
  }
  const std::uint64_t last = seg_end_ - 1;
  Seg& l = seg(last);
  if (l.hard_stop) return;
  l.hard_stop = true;
  hard_q_[(hard_head_ + hard_n_) % hard_q_.size()] = last;
  ++hard_n_;
}

void SampleSearch::resume() {
  if (stop_at_start_) {
    stop_at_start_ = false;
    return;
  }
  if (!at_stop_) return;
  at_stop_ = false;
  while (hard_n_ > 0 && joint_s(hard_q_[hard_head_]) <= last_commit_.s) {
    hard_head_ = (hard_head_ + 1) % hard_q_.size();
    --hard_n_;
  }
  front_ = committed_;
  restart_at_rest();
}

double SampleSearch::brake_rest_mm() {
  if (seg_end_ == 0) return popped_s_;
  Node n{popped_sp_, popped_s_, seg_of(popped_s_, last_commit_.seg), -1};
  const std::uint64_t c = popped_n_ > 0 ? popped_n_ - 1 : 0;
  const double end = terminal();
  for (std::size_t k = 1; k < out_reserve_ && n.s > n.sp; ++k) {
    ratio_ = ratio_at(c + k);
    Cand best{};
    if (!smallest_step(n, best)) {
      // (Cannot happen: pop() certified the tool's sample by this very brake.) The tangential
      // braking distance from the last step, and that step again.
      const double d = n.s - n.sp;
      return n.s + brake_distance(d, 0) + d + a_;
    }
    const double d2 = best.s2 - n.s;
    n = Node{n.s, best.s2, best.seg2, -1};
    if (n.s == end && d2 <= a_) break;
  }
  return n.s;
}

bool SampleSearch::stop_at(double s_mm) {
  if (seg_end_ == 0 || s_mm <= popped_s_ || hard_n_ == hard_q_.size()) return false;
  const std::uint64_t j = seg_of(std::nextafter(s_mm, 0.0), last_commit_.seg);
  Seg& g = seg(j);
  if (g.hard_stop || std::abs(joint_s(j) - s_mm) > kRound) return false;
  // In path order: after the stops at the tool (resume() drops them), before those ahead.
  const std::size_t n = hard_q_.size();
  hard_head_ = (hard_head_ + n - 1) % n;
  std::size_t i = 0;
  for (; i < hard_n_ && hard_q_[(hard_head_ + i + 1) % n] < j; ++i) {
    hard_q_[(hard_head_ + i) % n] = hard_q_[(hard_head_ + i + 1) % n];
  }
  hard_q_[(hard_head_ + i) % n] = j;
  ++hard_n_;
  g.hard_stop = true;
  g.stop = true;
  asked_ = j;
  // Planned again from the tool's sample, the effective caps made current ahead of the front
  // (restart() → refresh_eff()): the guide brakes for the new stop.
  restart(or_, 0);
  return true;
}

void SampleSearch::lift_stop() {
  const std::uint64_t j = asked_;
  asked_ = kNoSegment;
  // Reached (the tool rests on it): resume() drops it from the stops.
  if (j == kNoSegment || j < seg_base_ || j >= seg_end_ || joint_s(j) <= popped_s_) return;
  const std::size_t n = hard_q_.size();
  std::size_t i = 0;
  while (i < hard_n_ && hard_q_[(hard_head_ + i) % n] != j) ++i;
  if (i == hard_n_) return;
  for (; i + 1 < hard_n_; ++i) hard_q_[(hard_head_ + i) % n] = hard_q_[(hard_head_ + i + 1) % n];
  --hard_n_;
  seg(j).hard_stop = false;
  if (j + 1 < seg_end_) join(j);  // else it stays the window's end
  restart(or_, 0);
}

double SampleSearch::ratio_at(std::uint64_t cycle) const {
  double r = or_;
  for (std::size_t i = 0; i < allow_n_; ++i)
    if (cycle <= allow_[i].until) r = std::max(r, allow_[i].ratio);
  return r;
}

void SampleSearch::restart(double ratio, std::size_t ramp_cycles) {
  ++stats_.restarts;
  const std::uint64_t c = popped_n_ > 0 ? popped_n_ - 1 : 0;
  // The checker judges a sample by the largest override among the samples of the last ramp:
  // each override a decrease replaces stands until `ramp_cycles` after its last sample.
  std::size_t n = 0;
  for (std::size_t i = 0; i < allow_n_; ++i)
    if (allow_[i].until > c && allow_[i].ratio > ratio) allow_[n++] = allow_[i];
  allow_n_ = n;
  if (ramp_cycles > 0 && or_ > ratio) {
    if (allow_n_ == allow_.size()) {
      // Full: the one that expires first goes (less allowance: the plan brakes sooner).
      std::size_t first = 0;
      for (std::size_t i = 1; i < allow_n_; ++i)
        if (allow_[i].until < allow_[first].until) first = i;
      allow_[first] = allow_[--allow_n_];
    }
    allow_[allow_n_++] = {or_, c + ramp_cycles};
  }
  or_ = ratio;
  eff_fresh_ = seg_base_;  // refresh_eff() makes them current ahead of the front
  // At rest on a stop or at the end, with nothing left to pop: the new override applies from
  // the resume (planning now would move the tool while the kernel handles the stop's event).
  if ((at_stop() || finished_) && out_count_ == 0) return;
  out_count_ = 0;
  committed_ = front_ = c;
  last_commit_ = Node{popped_sp_, popped_s_, seg_of(popped_s_, last_commit_.seg), 0};
  beam_.assign(1, last_commit_);
  hist(front_, 0) = {popped_s_, -1};
  finished_ = false;
  at_stop_ = false;
}

void SampleSearch::idle() {
  // Only at rest with nothing planned ahead: the root state just moves to the next cycle.
  if (out_count_ != 0 || front_ != committed_ || last_commit_.sp != last_commit_.s) return;
  ++popped_n_;
  front_ = committed_ = popped_n_ - 1;
  popped_sp_ = popped_s_;
  if (!beam_.empty()) {
    hist(front_, 0) = {last_commit_.s, -1};
    beam_.assign(1, Node{last_commit_.s, last_commit_.s, last_commit_.seg, 0});
  }
}

void SampleSearch::brake_now() {
  restart(or_, 0);
  recover();
}

bool SampleSearch::advance(bool near_window_end) {
  if (finished_ || failed_ || at_stop() || seg_end_ == 0) return false;
  if (out_.size() - out_count_ < out_reserve_) return false;
  double far = 0;
  for (const Node& n : beam_) far = std::max(far, n.s);
  const double window_end = joint_s(seg_end_ - 1);
  const double end = terminal();
  refresh_eff(far + reach_mm_);
  // Without a stop ahead the front keeps a braking distance from the window's end.
  if (end == kInf && !near_window_end && far + reach_mm_ >= window_end) return false;
  ratio_ = ratio_at(front_ + 1);
  guide_cycle_ = front_ + 1;

  std::fill(bin_n_.begin(), bin_n_.end(), 0);
  std::int64_t done = -1;
  for (std::size_t bi = 0; bi < beam_.size() && done < 0; ++bi) {
    const Node nd = beam_[bi];
    std::size_t count = 0;
    expand(nd, count);
    for (std::size_t i = 0; i < count; ++i) {
      const Cand& c = cands_[i];
      const double d2 = c.s2 - nd.s;
      if (c.s2 == end) {
        if (d2 <= a_) {
          done = static_cast<std::int64_t>(bi);
          break;
        }
        continue;
      }
      offer(Node{nd.s, c.s2, c.seg2, static_cast<std::int32_t>(bi)}, c.ok == 2 ? 0 : 1);
    }
  }
  stats_.expanded += beam_.size();
  ++stats_.cycles;
  if (done >= 0) {
    // The end point or a stop: commit the lineage to it (it ends at rest: no brake needed).
    auto i = static_cast<std::size_t>(done);
    const auto len = static_cast<std::size_t>(front_ - committed_);
    for (std::size_t k = len; k-- > 0;) {
      const Hist& h = hist(committed_ + 1 + k, i);
      trace_[k] = Node{0, h.s, 0, 0};
      i = static_cast<std::size_t>(h.parent);
    }
    for (std::size_t k = 0; k < len; ++k) {
      last_commit_ = Node{last_commit_.s, trace_[k].s, seg_of(trace_[k].s, last_commit_.seg), -1};
      emit(last_commit_, committed_ + 1 + k);
    }
    last_commit_ = Node{last_commit_.s, end, seg_of(end, last_commit_.seg), -1};
    emit(last_commit_, committed_ + 1 + len);
    committed_ = front_ = front_ + 1;
    reached_terminal();
    return true;
  }
  std::size_t kept = 0;
  for (const std::size_t nb : bin_n_) kept += nb;
  if (kept == 0) {
    recover();
    return true;
  }
  ++front_;
  beam_.clear();
  for (std::size_t b = 0; b < bin_n_.size(); ++b) {
    for (std::size_t k = 0; k < bin_n_[b]; ++k) {
      const Node& c = bins_[b * opt_.per_bin + k];
      hist(front_, beam_.size()) = {c.s, c.parent};
      beam_.push_back(c);
      beam_.back().parent = static_cast<std::int32_t>(beam_.size() - 1);
    }
  }
  stats_.max_beam = std::max(stats_.max_beam, beam_.size());
  if (front_ - committed_ > opt_.max_lag_cycles) {
    force_commit();
  } else if (front_ % kCoalesceEvery == 0) {
    find_coalescence();
  }
  return true;
}

}  // namespace cncore::motion
