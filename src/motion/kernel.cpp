// The motion kernel: execution-data buffer → acc/dec (look-ahead + moving average) → shape
// interpolation (carrying the remainder across blocks) → events → post-interpolation per-axis
// moving average → Sample.
#include "motion/kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "motion/accel_limited.hpp"
#include "motion/moving_average.hpp"
#include "motion/piece_lines.hpp"
#include "motion/search_accdec.hpp"
#include "planner/buffer.hpp"
#include "planner/segment.hpp"
#include "planner/turn_window.hpp"

namespace cncore::motion {

using planner::ItemKind;
using planner::Segment;

KernelOptions kernel_options_for(const MachineConfig& machine) {
  KernelOptions o;
  switch (machine.accdec) {
    case AccDecKind::kAcceleration:
      o.accdec = AccDecType::kAcceleration;
      break;
    case AccDecKind::kSearch:
      o.accdec = AccDecType::kSearch;
      break;
    default:
      o.accdec = AccDecType::kMovingAverage;
  }
  o.bound_resultant_accel = machine.bound_resultant_accel;
  return o;
}

namespace {

// The types that plan with constant acceleration (the acceleration type and the search): no
// moving average, so no ramp terms in Vb and rapids at the configured rate.
bool accel_type(const KernelOptions& o) {
  return o.accdec != AccDecType::kMovingAverage && o.mode == Mode::kLookahead;
}

planner::Limits kernel_limits(const MachineConfig& m, const KernelOptions& o) {
  planner::Limits l = planner::make_limits(m, o.bound_resultant_accel);
  // No moving average to outrun: rapids at the configured rapid rate.
  if (accel_type(o)) l.rapid_pc = m.rapid_mm_min / 60.0 * m.period_s;
  return l;
}

// The limits segments are built with. The moving average's ramp terms of Vb (per-axis
// (d/T)·v, arcs (1 + 1/T)) do not apply to the acceleration-limited type, which bounds the
// tangential acceleration per segment itself (accel_limited.cpp): T → ∞ removes them.
planner::Limits segment_limits(const planner::Limits& lim, const KernelOptions& o) {
  planner::Limits l = lim;
  if (accel_type(o)) l.t_cycles = 1u << 30;
  return l;
}

std::unique_ptr<AccDec> make_accdec(const planner::SegmentBuffer& buf, const planner::Limits& lim,
                                    const KernelOptions& o, const MachineConfig& m) {
  if (accel_type(o) && o.accdec == AccDecType::kSearch) {
    if (lim.t2_cycles > 1 || lim.post_filter()) {
      throw std::invalid_argument(
          "acc/dec type \"search\" runs without a jerk limit and without a post filter (not "
          "supported yet)");
    }
    return std::make_unique<SearchAccDec>(lim, std::max<std::size_t>(64, 2 * buf.capacity()));
  }
  if (accel_type(o)) {
    return std::make_unique<AccelLimitedAccDec>(buf, lim, m.max_override_pct / 100.0,
                                                o.check_reference_walk);
  }
  return std::make_unique<MovingAverageAccDec>(buf, lim, o.mode, m.max_override_pct / 100.0,
                                               o.check_reference_walk);
}

}  // namespace

struct Kernel::Impl {
  Impl(const MachineConfig& m, const KernelOptions& o)
      : machine(m),
        options(o),
        lim(kernel_limits(m, o)),
        seg_lim(segment_limits(lim, o)),
        // Two items per block at most (an exact-stop block adds its stop event).
        buf(std::max<std::size_t>(4, static_cast<std::size_t>(m.lookahead_blocks) + 2)),
        // (The largest step: the top speed or the rapid rate, and one more cycle's rise.)
        turns(buf.capacity(), 1.01 * (std::max(lim.vmax_pc, lim.rapid_pc) + lim.amax_pc2)),
        acc_owner(make_accdec(buf, lim, o, m)),
        acc(*acc_owner),
        ma(dynamic_cast<MovingAverageAccDec*>(acc_owner.get())),
        al(dynamic_cast<AccelLimitedAccDec*>(acc_owner.get())),
        barriers(buf.capacity()),
        events(buf.capacity()),
        post_ring(lim.post_filter() ? lim.post_cycles : 1),
        // Merged lines come only when the block source merges (sim::make_line_merger).
        pieces(m.merge_tolerance_mm > 0 && o.mode != Mode::kStop ? PieceLines::kCapacity : 0) {
    for (std::size_t i = 0; i < kMaxAxes; ++i) last_end[i] = m.start_position[i];
    position = last_end;
    path_position = last_end;
    for (auto& p : post_ring) p = last_end;
    post_sum = static_cast<double>(post_ring.size()) * last_end;
    set_override(o.override_pct);
  }

  void set_override(double pct) {
    override_pct = std::clamp(std::isfinite(pct) ? pct : 0.0, 0.0, machine.max_override_pct);
    // Divided here, once per change, not every cycle: the ratio starts the cycle's chain of
    // dependent operations (Uc = F·OR → limiter → filter → point).
    or_ratio = override_pct / 100.0;
  }

  // A block takes up to three items: a stop before it, itself, an exact stop after it. The items
  // the tool has passed are dropped here, on the producer's side, rather than in step(): a
  // cycle that passes many tiny segments would otherwise pay for each of them in the real-time
  // path. The producer asks before every push, so the buffer is the same when step() runs.
  bool wants_block() {
    retire();
    return buf.size() + 3 <= buf.capacity() && !pieces.full();
  }

  void pop_event() {
    ev_head = ev_head + 1 == events.size() ? 0 : ev_head + 1;
    --ev_size;
  }

  void push_event(const Segment& ev) {
    const std::uint64_t idx = buf.push(ev);
    // Events already retired from the buffer are no longer needed: the ring never holds more
    // than the buffer's capacity.
    while (ev_size > 0 && events[ev_head] < buf.begin_index()) pop_event();
    events[(ev_head + ev_size) % events.size()] = idx;
    ++ev_size;
    if (ev.barrier) {
      acc.on_barrier();
      barriers[(bq_head + bq_size) % barriers.size()] = idx;
      ++bq_size;
      barrier_since_motion = true;
    }
  }

  void push(const Block& b) {
    if (b.piece) {  // a programmed piece of the merged line before it: its line, not planned
      pieces.on_piece(b);
      return;
    }
    Segment ev;
    ev.start = last_end;
    ev.end = last_end;
    ev.s0_mm = total_mm;
    ev.line = b.line;
    switch (b.kind) {
      case BlockKind::kDwell:
        ev.kind = ItemKind::kDwell;
        ev.barrier = true;
        ev.dwell_cycles =
            static_cast<std::uint32_t>(std::lround(std::max(0.0, b.dwell_s) / lim.period_s));
        push_event(ev);
        return;
      case BlockKind::kAux:
        ev.kind = ItemKind::kAux;
        ev.barrier = b.aux_waits;
        ev.aux_letter = b.aux_letter;
        ev.aux_value = b.aux_value;
        ev.aux_p = b.aux_p;
        push_event(ev);
        return;
      default:
        break;
    }
    Segment seg = planner::make_motion_segment(b, seg_lim);
    if (seg.length_mm > 0) {
      seg.s0_mm = total_mm;
      const bool joint = have_motion && !barrier_since_motion && last_motion >= buf.begin_index();
      const bool slow_stops = !accel_type(options);
      // The moving average needs this same value in on_joint: computed once (push is the
      // per-block cost that P7's 100x finer programs multiply).
      AxisVec a_end, b_start;  // the directions at the joint (the acceleration type's zones)
      const double vg =
          joint ? planner::joint_speed_pc(buf[last_motion], seg, lim, slow_stops, a_end, b_start)
                : 0;
      if (joint && vg <= 0) {
        // A joint that must be passed at speed 0 (exact path through the post filter): a stop
        // that also waits for the post filter to settle, so the corner is not rounded.
        push_event(stop_event(b.line));
      }
      any_fixed = any_fixed || seg.override_fixed;
      const std::uint64_t idx = buf.push(seg);
      if (b.pieces > 0) pieces.on_line(b, idx, seg.s0_mm);
      // A chain of segments shorter than a step: the turn within one step before the joint
      // (planner/turn_window.hpp) may hold the passing speed lower than the corner alone.
      const bool chained = joint && vg > 0;
      turns.on_segment(buf[idx], chained);
      planner::Turn turn;
      const double vg_chain =
          chained ? turns.chain_speed_pc(buf, last_motion, idx, vg, lim, turn) : vg;
      if (joint && al != nullptr) {
        al->set_next_corner(last_motion, vg_chain, a_end, b_start, turn);  // (slow_stops false)
      }
      acc.on_segment(idx, buf[idx]);
      if (have_motion && !barrier_since_motion && last_motion >= buf.begin_index()) {
        if (ma != nullptr) {
          ma->on_joint(last_motion, buf[last_motion], buf[idx], vg_chain);  // same joint
        } else {
          acc.on_joint(last_motion, buf[last_motion], buf[idx]);
        }
      }
      have_motion = true;
      barrier_since_motion = false;
      last_motion = idx;
      // The end of this block, as a sum of lengths: the tail stop and every later s0 use it.
      total_mm = seg.end_mm();
      last_end = seg.end;
    }
    if (b.path_mode == PathMode::kExactStop) {
      // Exact stop: speed 0 and settled at the end of the block (an event with no action).
      push_event(stop_event(b.line));
    }
  }

  Segment stop_event(std::uint32_t line) const {
    Segment stop;
    stop.kind = ItemKind::kDwell;
    stop.barrier = true;
    stop.start = last_end;
    stop.end = last_end;
    stop.s0_mm = total_mm;
    stop.line = line;
    return stop;
  }

  double stop_mm() const {
    double s = total_mm;  // the buffer's last end point (a stop until its successor comes)
    if (bq_size > 0) s = std::min(s, buf[barriers[bq_head]].s0_mm);
    return std::min(s, block_stop_mm);
  }

  // Kernel::request_stop_at_block_end, taken at the start of the cycle after the request: the
  // first motion block end e ahead of the tool at or after the acc/dec's stop reach that it
  // accepts, or the stop already ahead when that comes first. Tries at most the buffer's items
  // (its configured capacity), in this cycle only; mostly the first end it tries.
  template <typename A>
  void choose_block_stop(A& a) {
    const double tool = a.tool_mm();
    const double ahead = stop_mm();  // (block_stop_mm is +∞ here)
    double chosen = ahead > tool ? ahead : kNoStop;
    if (!buf.empty() && std::max(out_idx, buf.begin_index()) < buf.end_index()) {
      const double reach = a.stop_reach_mm();
      // The first item ending after max(tool, reach − ulp): its end is > tool and ≥ reach.
      const double from = std::max(tool, std::nextafter(reach, -kNoStop));
      for (std::uint64_t k = buf.seek(std::max(out_idx, buf.begin_index()), from);
           k < buf.end_index(); ++k) {
        const double e = buf.end_mm_of(k);
        if (e >= chosen) break;
        if (buf.is_motion(k) && e > tool && e >= reach && a.can_stop_at(e)) {
          chosen = e;
          break;
        }
      }
    }
    if (chosen == kNoStop) return;  // nothing ahead yet: tried again next cycle
    stop_asked = false;
    block_stop_mm = chosen;
    a.on_stop_request(chosen);
  }

  bool stopped_at_block_end() const {
    return block_stop_mm < kNoStop && acc.tool_mm() >= block_stop_mm && acc.at_rest() &&
           post_settled();
  }

  void release_block_stop() {
    stop_asked = false;
    if (block_stop_mm == kNoStop) return;
    block_stop_mm = kNoStop;
    acc.on_stop_release();
  }

  bool post_settled() const { return !lim.post_filter() || post_still >= lim.post_cycles; }

  // Moves the output cursor to the item under the tool, handling events on the way. Runs of
  // motion items are skipped by a galloping search up to the next event (events), so a cycle
  // that passes k tiny segments costs O(log k), not O(k).
  void advance_output(double tool, Sample& out) {
    while (out_idx < buf.end_index()) {
      const bool has_next = out_idx + 1 < buf.end_index();
      // Motion items from the compact arrays: a cycle that leaves its item loads no Segment.
      if (buf.is_motion(out_idx)) {
        if (tool >= buf.end_mm_of(out_idx) && has_next) {
          while (ev_size > 0 && events[ev_head] < out_idx) pop_event();
          const std::uint64_t next_event = ev_size > 0 ? events[ev_head] : UINT64_MAX;
          // The walk stops at the first motion item the tool is inside, the last item, or the
          // next event, whichever comes first.
          // Hint: as many items as the last cycle that left its item skipped.
          const std::uint64_t from = out_idx;
          out_idx = buf.seek(from + 1, tool, next_event, from + out_skip);
          out_skip = out_idx - from;
          continue;
        }
        return;
      }
      Segment& it = buf[out_idx];
      if (!it.done) {
        if (tool < it.s0_mm) return;
        if (it.barrier && (!acc.at_rest() || !post_settled())) return;
        if (it.kind == ItemKind::kDwell) {
          if (!dwelling) {
            dwelling = true;
            dwell_left = it.dwell_cycles;
          }
          if (dwell_left > 0) {
            --dwell_left;
            return;
          }
          dwelling = false;
        } else {
          if (out.aux_letter != 0) return;  // one event per sample; the next one next cycle
          out.aux_letter = it.aux_letter;
          out.aux_value = it.aux_value;
          out.aux_p = it.aux_p;
        }
        it.done = true;
        if (it.barrier) {
          bq_head = (bq_head + 1) % barriers.size();
          --bq_size;
        }
      }
      if (!has_next) return;
      ++out_idx;
    }
  }

  // The item under the tool, nullptr before the first block.
  const Segment* current() const {
    return (buf.empty() || out_idx >= buf.end_index()) ? nullptr : &buf[out_idx];
  }

  // The point on the path at `tool` on item `cur` (the item under the tool; nullptr: none yet).
  AxisVec interpolate(const Segment* cur, double tool) const {
    if (cur == nullptr) return last_end;
    if (cur->kind != ItemKind::kMotion) return cur->end;
    return cur->point_at(tool - cur->s0_mm);
  }

  void retire() {
    if (al != nullptr) {
      retire_with(*al);
    } else if (ma != nullptr) {
      retire_with(*ma);
    } else {
      retire_with(acc);
    }
  }
  // With the acc/dec's own (final) type: its calls per retired item are direct ones.
  template <typename A>
  void retire_with(A& a) {
    while (buf.begin_index() < out_idx) {
      const std::uint64_t i = buf.begin_index();
      // (The kind from the compact array: the retired item's Segment is cold.)
      if (buf.is_motion(i) && a.holds(i) && (buf.size() + 3 <= buf.capacity() || !a.detach(i))) {
        break;
      }
      a.on_retire(i);
      buf.pop_front();
    }
  }

  // The set-point sent to the servos for path point p (stored in `position` and returned: the
  // caller fills the sample from the returned value, not by reloading the member, whose
  // piecewise stores a wider reload could not forward from).
  AxisVec post_filter(const AxisVec& p) {
    if (!lim.post_filter()) {
      position = p;
      return p;
    }
    // Per-axis moving average over Tp cycles (running sum; exact once the path stood still
    // for Tp cycles). Ring indices by compare, not `%` (two divisions per cycle).
    const std::size_t n = post_ring.size();
    const std::size_t prev = post_pos == 0 ? n - 1 : post_pos - 1;
    post_still = (p == post_ring[prev]) ? post_still + 1 : 0;
    post_sum = post_sum + (p - post_ring[post_pos]);
    post_ring[post_pos] = p;
    post_pos = post_pos + 1 == n ? 0 : post_pos + 1;
    position = post_still >= lim.post_cycles ? p : (1.0 / static_cast<double>(n)) * post_sum;
    return position;
  }

  // The channels fill() does not set, at their defaults (as Sample{} has them). Assigning them
  // one by one is much cheaper than `out = Sample{}`, which compiles to a `rep stos` of the
  // whole sample on every cycle.
  static void clear_events(Sample& out) {
    static_assert(sizeof(Sample) == 184, "a field was added to Sample: reset it here too");
    out.load_pct = std::nan("");
    out.load_target_pct = std::nan("");
    out.ref = std::nan("");
    out.aux_letter = 0;
    out.aux_value = 0;
    out.aux_p = 0;
  }

  // line: the source line under the tool (0: none); pos, path: this cycle's position and
  // path_position.
  void fill(Sample& out, std::uint32_t line, const AxisVec& pos, const AxisVec& path,
            double speed_pc) const {
    out.t_s = static_cast<double>(cycle) * lim.period_s;
    out.line = line;
    out.position = pos;
    out.path_position = path;
    out.feed_mm_min = speed_pc / lim.period_s * 60.0;
    out.override_pct = override_pct;
    out.correction = correction_now;
  }

  // Override mode "replace" of the direction correction (spec 03): on segments marked
  // override_fixed the operator's override does not act. The segment under the commanded
  // position decides, as it does for the feed inside the acc/dec (a switch at a joint acts like
  // an override change there, which the look-ahead handles for any override ≤ ORmax).
  double cycle_or_ratio() {
    const double r = or_ratio;
    if ((!any_fixed && rapid_or_ratio < 0) || buf.empty()) return r;
    const double cmd = acc.commanded_mm();
    cmd_idx = std::max(cmd_idx, buf.begin_index());
    if (cmd_idx >= buf.end_index()) return r;
    cmd_idx = buf.seek(cmd_idx, cmd);
    const Segment& seg = buf[cmd_idx];
    if (seg.kind != ItemKind::kMotion) return r;
    if (seg.override_fixed) return 1.0;
    return seg.rapid && rapid_or_ratio >= 0 ? rapid_or_ratio : r;
  }

  // Through the acc/dec's final type: direct (inlined) calls, no virtual dispatch.
  bool step(Sample& out) {
    if (ma != nullptr) return step_with(*ma, out);
    if (al != nullptr) return step_with(*al, out);
    return step_with(acc, out);
  }

  template <typename A>
  bool all_done_with(const A& a) const {
    if (!ended || bq_size > 0 || !a.at_rest() || !post_settled()) return false;
    if (buf.empty()) return true;
    if (out_idx + 1 < buf.end_index()) return false;
    const Segment& last = buf[out_idx];
    return last.kind == ItemKind::kMotion ? a.tool_mm() >= last.end_mm() : last.done;
  }

  template <typename A>
  bool step_with(A& a, Sample& out) {
    if (!started) {
      started = true;
      out = Sample{};
      const Segment* cur = current();
      fill(out, cur == nullptr ? 0 : cur->line, position, path_position, 0);
      return true;
    }
    if (all_done_with(a)) return false;
    if (stop_asked) choose_block_stop(a);
    ++cycle;
    CycleInput in;
    in.or_ratio = cycle_or_ratio();
    in.hold = hold;
    in.stop_mm = stop_mm();
    a.step(in);
    clear_events(out);
    const double tool = a.tool_mm();
    advance_output(tool, out);
    // retire() below drops only items before out_idx: cur stays valid for fill().
    const Segment* cur = current();
    const AxisVec path = interpolate(cur, tool);
    path_position = path;
    if (cur != nullptr && cur->kind == ItemKind::kMotion) {
      correction_now = cur->correction;  // spec 03: C of the segment under the tool
    }
    const AxisVec pos = post_filter(path);
    // Once the program has ended the producer stops asking wants_block(): retire here then.
    if (ended) retire_with(a);
    // The line under the tool: on a merged line, its programmed piece's.
    std::uint32_t line = 0;
    if (cur != nullptr) {
      line = cur->kind == ItemKind::kMotion ? pieces.line_at(out_idx, tool, cur->line) : cur->line;
    }
    fill(out, line, pos, path, a.tool_speed_pc());
    return true;
  }

  MachineConfig machine;
  KernelOptions options;
  planner::Limits lim;
  planner::Limits seg_lim;
  planner::SegmentBuffer buf;
  planner::TurnWindow turns;
  std::unique_ptr<AccDec> acc_owner;
  AccDec& acc;
  MovingAverageAccDec* ma;  // acc when it is the moving average (non-virtual fast path), else null
  AccelLimitedAccDec* al;   // acc when it is the acceleration-limited type, else null

  AxisVec last_end;     // end of the last pushed motion
  double total_mm = 0;  // its path position
  bool have_motion = false;
  bool barrier_since_motion = false;
  std::uint64_t last_motion = 0;
  // Rings sized by the window (huge_pages.hpp: cheap to touch at construction).
  template <typename T>
  using Ring = std::vector<T, planner::HugePageAllocator<T>>;
  Ring<std::uint64_t> barriers;  // unprocessed stop events, in order (fixed ring)
  std::size_t bq_head = 0, bq_size = 0;
  Ring<std::uint64_t> events;  // indices of event items not yet passed (fixed ring)
  std::size_t ev_head = 0, ev_size = 0;

  bool ended = false, started = false, hold = false;
  static constexpr double kNoStop = std::numeric_limits<double>::infinity();
  bool stop_asked = false;         // request_stop_at_block_end, taken by the next step()
  double block_stop_mm = kNoStop;  // the requested stop at a block end (+∞: none)
  double override_pct = 100;
  double or_ratio = 1;         // override_pct / 100 (set_override)
  double rapid_or_ratio = -1;  // rapids' own ratio (set_rapid_override); < 0: or_ratio
  std::uint64_t cycle = 0;
  std::uint64_t out_idx = 0;
  std::uint64_t out_skip = 1;  // items the output cursor last moved by (advance_output's hint)
  bool any_fixed = false;      // some segment ignores the override (correction "replace")
  std::uint64_t cmd_idx = 0;   // buffer item under the commanded position (cycle_or_ratio)
  double correction_now = std::nan("");
  bool dwelling = false;
  std::uint32_t dwell_left = 0;

  AxisVec path_position, position;
  std::vector<AxisVec> post_ring;
  std::size_t post_pos = 0;
  AxisVec post_sum;
  std::uint32_t post_still = UINT32_MAX / 2;  // settled at start
  PieceLines pieces;  // the programmed pieces of the merged lines in the buffer
};

Kernel::Kernel(const MachineConfig& machine, const KernelOptions& options)
    : impl_(std::make_unique<Impl>(machine, options)) {}
Kernel::~Kernel() = default;
bool Kernel::wants_block() const {
  return impl_->wants_block();
}
void Kernel::push(const Block& block) {
  impl_->push(block);
}
void Kernel::end_of_program() {
  if (!impl_->ended) impl_->acc.on_end_of_program();
  impl_->ended = true;
}
bool Kernel::step(Sample& out) {
  return impl_->step(out);
}
void Kernel::set_override(double pct) {
  impl_->set_override(pct);
}

void Kernel::set_rapid_override(double pct) {
  impl_->rapid_or_ratio = std::isfinite(pct) && pct >= 0 ? std::min(pct, 100.0) / 100.0 : -1;
}
void Kernel::set_feed_hold(bool hold) {
  impl_->hold = hold;
}
void Kernel::request_stop_at_block_end() {
  if (impl_->block_stop_mm == Impl::kNoStop) impl_->stop_asked = true;
}
bool Kernel::stopped_at_block_end() const {
  return impl_->stopped_at_block_end();
}
void Kernel::release_stop_at_block_end() {
  impl_->release_block_stop();
}
std::uint64_t Kernel::reference_mismatches() const {
  if (const auto* ma = dynamic_cast<const MovingAverageAccDec*>(&impl_->acc)) {
    return ma->reference_mismatches();
  }
  const auto* al = dynamic_cast<const AccelLimitedAccDec*>(&impl_->acc);
  return al != nullptr ? al->reference_mismatches() : 0;
}
double Kernel::filter_time_s() const {
  return impl_->lim.span_cycles() * impl_->lim.period_s;
}

}  // namespace cncore::motion
