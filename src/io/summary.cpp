#include "io/summary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "motion/piece_lines.hpp"

namespace cncore::io {

namespace {

constexpr std::size_t kSlowCandidates = 64;  // bounded candidate set for the slowest spots
constexpr std::size_t kSlowReported = 5;
// Blocks searched ahead when the line changes: a cycle may pass hundreds of sub-µm pieces.
constexpr std::size_t kMatchWindow = 4096;

std::string axis_name(std::size_t i) {
  return {static_cast<char>(std::tolower(static_cast<unsigned char>(kAxisLetters[i])))};
}

// m = max(m, a / h) for a ≥ 0 (or NaN) and h > 0, dividing only when the quotient can matter.
// When a < b = m·h·(1 − 10⁻⁹) (b normal; every product rounded once, relative error ≤ 2⁻⁵³),
// a/h rounded is below m·(1 − 10⁻⁹)·(1 + 2⁻⁵³)³ < m: max keeps m, so the result is the same
// double as dividing every time (m·h overflowing to b = ∞: a/h ≤ DBL_MAX/h < m). Almost every cycle
// takes the early return once the run's maximum has been reached.
constexpr double kBelow = 1 - 1e-9;
inline void raise_max_quotient(double& m, double a, double h) {
  if (!(a > 0)) return;  // a/h is 0 or NaN, which max never takes over m ≥ 0 (idle axes)
  const double b = m * h * kBelow;
  if (b >= std::numeric_limits<double>::min() && a < b) return;
  m = std::max(m, a / h);
}
// m = max(m, √q / h), q ≥ 0 (or NaN): q < b² with b as above gives √q / h < m the same way
// (b² rounded once more, the root once: still far inside the 10⁻⁹ margin).
inline void raise_max_root_quotient(double& m, double q, double h) {
  if (!(q > 0)) return;  // as above
  const double b = m * h * kBelow;
  const double b2 = b * b;
  if (b2 >= std::numeric_limits<double>::min() && q < b2) return;
  m = std::max(m, std::sqrt(q) / h);
}

// Distance from p to the segment a-b.
double segment_distance(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 ab = b - a;
  const double len2 = dot(ab, ab);
  double u = len2 > 0 ? dot(p - a, ab) / len2 : 0;
  u = std::clamp(u, 0.0, 1.0);
  return norm(p - (a + u * ab));
}

}  // namespace

SummaryObserver::SummaryObserver(const MachineConfig& machine, std::string mode)
    : machine_(machine),
      // The kernel holds at most its buffer's blocks and its ring's pieces; on_block keeps no
      // more than that + 1024 (the ring grows to it only as far as a program fills it).
      pending_(1024),
      pending_max_(static_cast<std::size_t>(machine.lookahead_blocks) +
                   motion::PieceLines::kCapacity + 1024),
      recent_(kRecent),
      diff_(machine) {
  summary_.mode = std::move(mode);
  // Window of on-path points searched for the contour error: the post-interpolation filter
  // delays the set-point by at most its length; keep at least 20 ms in case the kernel smooths
  // corners on its own.
  const double window_s = std::max(machine.post_filter_s, 0.02);
  const double cycles = std::ceil(window_s / machine.period_s) + 2;
  window_s_ = cycles * machine.period_s;
  path_ring_.resize(static_cast<std::size_t>(std::min(cycles, 512.0)));
  top_.reserve(kSlowCandidates);
  constexpr double kSlack = 1e-6;  // travel_check: a set-point this far outside is still inside
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const AxisConfig& a = machine.axes[i];
    if (a.enabled) travel_unwarned_ |= 1u << i;
    // Not checked: limits no position leaves (travel_check tests every axis).
    travel_lo_mm_[i] = a.enabled ? a.min_mm - kSlack : -std::numeric_limits<double>::infinity();
    travel_hi_mm_[i] = a.enabled ? a.max_mm + kSlack : std::numeric_limits<double>::infinity();
  }
}

void SummaryObserver::on_block(const Block& b) {
  // A merged line: its programmed pieces follow, and the samples name them.
  if (b.pieces > 0) return;
  double cap = 0;
  switch (b.kind) {
    case BlockKind::kRapid:
      cap = machine_.rapid_mm_min;
      ++summary_.blocks;
      pending_.push_back({b.line, cap, cap, true, true, false, b.last_line, ProgrammedMove(b)});
      break;
    case BlockKind::kLine:
    case BlockKind::kArc:
      cap = machine_.max_feed_mm_min;
      ++summary_.blocks;
      pending_.push_back(
          {b.line, b.feed_mm_min, cap, false, true, false, b.last_line, ProgrammedMove(b)});
      break;
    case BlockKind::kDwell:
      pending_.push_back({b.line, 0, 0, false, false, false, 0, ProgrammedMove{}});
      break;
    case BlockKind::kAux:
      break;
  }
  // The kernel never holds more than its buffer and its pieces; if lines never match (a kernel
  // that reports other line numbers), forget the oldest rather than grow.
  while (pending_.size() > pending_max_) pending_.pop_front();
}

// The block under the tool on `line`, matched in order against the blocks handed to the kernel
// (index into pending_; the ones before it the tool has passed). kNone when unknown. Where one
// line made several blocks (a spline's arcs, compensation's corner arcs, a canned cycle), the
// tool is on a later one once the nearest point of the earlier one is its end and the later one
// is no farther.
std::size_t SummaryObserver::match(std::uint32_t line, Vec3 pos) const {
  const std::size_t n = std::min(pending_.size(), kMatchWindow);
  std::size_t j = 0;
  while (j < n && pending_[j].line != line) ++j;
  if (j == n) return kNone;
  while (pending_[j].motion) {
    // The line's next move; its dwells (a cycle's, a thread's index wait) pass with it.
    std::size_t k = j + 1;
    while (k < n && pending_[k].line == line && !pending_[k].motion) ++k;
    if (k >= n || pending_[k].line != line) break;
    const ProgrammedMove::Nearest here = pending_[j].move.nearest(pos);
    if (here.along_mm < pending_[j].move.length_mm() - 1e-9) break;
    if (pending_[k].move.nearest(pos).distance_mm > here.distance_mm + 1e-9) break;
    j = k;
  }
  return j;
}

// The blocks before pending_[j] are passed: into the window of recent moves.
void SummaryObserver::pass(std::size_t j, double t_s) {
  for (std::size_t k = 0; k < j; ++k) {
    if (!pending_[k].motion) continue;
    recent_[recent_next_] = {pending_[k].move, t_s};
    recent_next_ = recent_next_ + 1 == recent_.size() ? 0 : recent_next_ + 1;
    recent_size_ = std::min(recent_size_ + 1, recent_.size());
  }
  pending_.drop_front(j);
}

// Distance from the set-point to the programmed path near the tool: the moves passed within
// the window (newest first), the block under the tool (pending_[j]), the two after it and the
// other moves of its line. A line whose moves retrace each other (a canned cycle's pecks, a
// lathe cycle's passes) can hold the match on an earlier move while the tool is on a later
// one: the tool is on one of the line's moves. Moves whose bounding sphere lies farther than
// the best so far are skipped.
double SummaryObserver::programmed_distance(Vec3 pos, std::size_t j, double t_s) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t ahead = std::min(pending_.size(), (j == kNone ? 0 : j) + 3);
  if (const std::size_t from = j == kNone ? 0 : j; from < pending_.size()) {
    // (kNone: the tool is on a line without moves, an M2 after a cycle: the line before.)
    const std::size_t n = std::min(pending_.size(), kMatchWindow);
    std::size_t e = from;
    while (e < n && pending_[e].line == pending_[from].line) ++e;
    ahead = std::max(ahead, e);
  }
  for (std::size_t k = 0; k < ahead; ++k) {
    const Pending& b = pending_[k];
    if (b.motion && b.move.distance_bound(pos) < best) {
      best = std::min(best, b.move.nearest(pos).distance_mm);
    }
  }
  std::size_t i = recent_next_;
  for (std::size_t k = 0; k < recent_size_; ++k) {
    i = i == 0 ? recent_.size() - 1 : i - 1;
    const Passed& p = recent_[i];
    if (p.t_s < t_s - window_s_) break;
    if (p.move.distance_bound(pos) < best) best = std::min(best, p.move.nearest(pos).distance_mm);
  }
  return best;
}

// Without programmed moves (a recorded trajectory, a table run): the distance to the polyline of
// recent on-path points. Ring indices step by compare instead of `%`.
double SummaryObserver::path_ring_distance(Vec3 pos, double lag_mm) {
  const std::size_t ring_n = path_ring_.size();
  double contour = lag_mm;
  std::size_t newer = ring_next_;
  for (std::size_t k = 1; k < ring_size_ && contour > 0; ++k) {
    // newer = ring_next_ − k, older = newer − 1 (mod the ring size)
    newer = newer == 0 ? ring_n - 1 : newer - 1;
    const std::size_t older = newer == 0 ? ring_n - 1 : newer - 1;
    contour = std::min(contour, segment_distance(pos, path_ring_[older], path_ring_[newer]));
  }
  return contour;
}

// Time lost on block b for dt_s of a cycle that moved len_mm on it, against its programmed
// feed × override: dt − len/F (the cycle ran at v = len/dt: dt·(1 − v/F)), 0 when v ≥ F.
void SummaryObserver::credit(Pending& b, double dt_s, double len_mm, const motion::Sample& s) {
  const double override_pct = s.override_pct;
  if (b.line != group_.line) {
    close_group();
    group_.line = b.line;
  }
  group_.time_s += dt_s;
  group_.length_mm += len_mm;
  if (b.motion && dt_s > 0 && !b.timed) {
    b.timed = true;
    ++summary_.blocks_timed;
  }
  // F as written × override, capped, as the kernel asks it (F20000 at 50 % on a 10 000 mm/min
  // machine runs at 10 000): computed again only when one of the three changes (a division per
  // cycle less; the same double).
  if (b.programmed_mm_min != target_feed_ || b.cap_mm_min != target_cap_ ||
      override_pct != target_override_) {
    target_feed_ = b.programmed_mm_min;
    target_cap_ = b.cap_mm_min;
    target_override_ = override_pct;
    target_ = std::min(b.programmed_mm_min * override_pct / 100, b.cap_mm_min);
  }
  const double target = target_;
  group_.programmed_feed_mm_min = target;
  group_.rapid = b.rapid;
  group_.last_line = b.last_line;
  double lost_s = 0;
  if (target > 0) {
    const double lost = dt_s - len_mm * 60 / target;
    if (lost > 0) {
      lost_s = lost;
      group_.lost_s += lost;
      summary_.time_lost_s += lost;
    }
  }
  if (listener_ != nullptr && b.motion) {
    listener_->on_share({&s, b.line, b.last_line, b.rapid, dt_s, len_mm, b.programmed_mm_min,
                         b.cap_mm_min, target, lost_s});
  }
}

// The cycle from the previous sample to s moved len_mm in dt_s and ended on pending_[j]: the
// blocks it passed share it by the distance the on-path point covered on each (what is left of
// the first, the whole of those between, the start of the last), at the cycle's speed.
void SummaryObserver::share(const motion::Sample& s, std::size_t j, double dt_s, double len_mm) {
  if (j == 0) {
    credit(pending_.front(), dt_s, len_mm, s);
    return;
  }
  const Vec3 path = s.path_position.xyz();
  auto covered = [&](std::size_t k) {
    const Pending& b = pending_[k];
    if (!b.motion) return 0.0;
    if (k == 0) return b.move.length_mm() - b.move.nearest(prev_path_).along_mm;
    if (k == j) return b.move.nearest(path).along_mm;
    return b.move.length_mm();
  };
  double total = 0;
  for (std::size_t k = 0; k <= j; ++k) total += covered(k);
  if (!(total > 0)) {
    credit(pending_[j], dt_s, len_mm, s);
    return;
  }
  for (std::size_t k = 0; k <= j; ++k) {
    const double w = covered(k) / total;
    if (w > 0) credit(pending_[k], dt_s * w, len_mm * w, s);
  }
}

void SummaryObserver::close_group() {
  if (group_.line == 0 || group_.time_s <= 0) {
    group_ = SlowSpot{};
    return;
  }
  group_.visits = 1;
  // A line group closes every few cycles on short segments: the candidates are searched only
  // when the line filter says the line may be among them.
  auto same = top_.end();
  if (top_lines_[group_.line % kLineFilter] > 0) {
    same = std::find_if(top_.begin(), top_.end(),
                        [&](const SlowSpot& s) { return s.line == group_.line; });
  }
  if (same != top_.end()) {
    same->lost_s += group_.lost_s;
    same->time_s += group_.time_s;
    same->length_mm += group_.length_mm;
    same->programmed_feed_mm_min = group_.programmed_feed_mm_min;
    same->visits += 1;
    if (group_.last_line != 0) same->last_line = group_.last_line;
    // lost_s only grows: the least candidate stays the least unless it grew itself.
    if (same - top_.begin() == static_cast<std::ptrdiff_t>(least_) && group_.lost_s != 0) {
      least_ = kNoLeast;
    }
  } else if (top_.size() < kSlowCandidates) {
    top_.push_back(group_);
    ++top_lines_[group_.line % kLineFilter];
    least_ = kNoLeast;
  } else {
    // The first candidate with the least lost_s (as std::min_element), found again only after
    // it changed.
    if (least_ == kNoLeast) {
      least_ = static_cast<std::size_t>(std::min_element(top_.begin(), top_.end(),
                                                         [](const SlowSpot& a, const SlowSpot& b) {
                                                           return a.lost_s < b.lost_s;
                                                         }) -
                                        top_.begin());
    }
    SlowSpot& least = top_[least_];
    if (group_.lost_s > least.lost_s) {
      --top_lines_[least.line % kLineFilter];
      ++top_lines_[group_.line % kLineFilter];
      least = group_;
      least_ = kNoLeast;
    }
  }
  group_ = SlowSpot{};
}

template <std::size_t N>
inline void SummaryObserver::travel_check(const motion::Sample& s) {
  // Every axis at once, without a branch per axis: the limits of axes not checked (disabled,
  // or already warned) are ±∞, which no position leaves (a NaN leaves none either). Axes from
  // N on are disabled.
  unsigned outside = 0;
  for (std::size_t i = 0; i < N; ++i) {
    const double p = s.position[i];
    outside |=
        static_cast<unsigned>(p < travel_lo_mm_[i]) | static_cast<unsigned>(p > travel_hi_mm_[i]);
  }
  if (outside != 0) travel_warn(s);
}

// Out of line: the check above stays small enough to inline into on_sample.
void SummaryObserver::travel_warn(const motion::Sample& s) {
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if ((travel_unwarned_ & (1u << i)) == 0) continue;
    const AxisConfig& a = machine_.axes[i];
    const double p = s.position[i];
    if (p < travel_lo_mm_[i] || p > travel_hi_mm_[i]) {
      travel_unwarned_ &= ~(1u << i);
      travel_lo_mm_[i] = -std::numeric_limits<double>::infinity();
      travel_hi_mm_[i] = std::numeric_limits<double>::infinity();
      const char* unit = a.rotary ? "deg" : "mm";
      summary_.warnings.push_back(fmt::format(
          "axis {} leaves its travel at line {} (t = {:.3f} s): {} = {:.3f} {}, travel {} … {} {}",
          kAxisLetters[i], s.line, s.t_s, kAxisLetters[i], p, unit, a.min_mm, a.max_mm, unit));
    }
  }
}

void SummaryObserver::add_event(const AuxEvent& event) {
  if (summary_.aux_events.size() < Summary::kMaxAuxEvents) summary_.aux_events.push_back(event);
  ++summary_.aux_event_count;
}

void SummaryObserver::on_sample(const motion::Sample& s) {
  on_samples(std::span<const motion::Sample>(&s, 1));
}

void SummaryObserver::on_samples(std::span<const motion::Sample> samples) {
  // Machines with X, Y, Z only (the usual case) take loops of 3 axes, fully unrolled: a
  // shorter cycle, and the next sample's work overlaps more of this one's divisions and root.
  if (diff_.used_axes() <= 3) {
    for (const motion::Sample& s : samples) sample<3>(s);
  } else {
    for (const motion::Sample& s : samples) sample<kMaxAxes>(s);
  }
}

// Size: the per-sample hot path of every run: the figures of one cycle (time, load, block under
// the tool, contour error, speeds and accelerations by differences) in one pass over the axes,
// kept together so the compiler unrolls and overlaps them (see on_samples).
template <std::size_t N>
void SummaryObserver::sample(const motion::Sample& s) {
  ++summary_.cycles;
  summary_.cycle_time_s = s.t_s;
  travel_check<N>(s);
  if (!std::isnan(s.correction)) {
    // NaN compares false: the first coefficient seen initialises both.
    if (!(s.correction >= summary_.correction_min)) summary_.correction_min = s.correction;
    if (!(s.correction <= summary_.correction_max)) summary_.correction_max = s.correction;
  }
  if (record_sample_events_ && s.aux_letter != 0) {
    add_event({s.t_s, s.line, s.aux_letter, s.aux_value});
  }
  // Spindle load (spec 04): each cycle with a reading counts for the time since the previous one.
  const double dt_s = have_previous_t_ ? s.t_s - previous_t_s_ : 0.0;
  have_previous_t_ = true;
  previous_t_s_ = s.t_s;
  if (!std::isnan(s.load_pct)) {
    LoadSummary& l = summary_.load;
    l.present = true;
    l.peak_load_pct = std::max(l.peak_load_pct, s.load_pct);
    load_sum_pct_ += s.load_pct;
    ++load_cycles_;
    l.mean_load_pct = load_sum_pct_ / static_cast<double>(load_cycles_);
    if (!std::isnan(s.load_target_pct) && s.load_pct > s.load_target_pct) {
      l.time_above_target_s += dt_s;
      if (s.load_pct > s.load_target_pct + LoadSummary::kBandPct) {
        l.time_above_target_band_s += dt_s;
      }
    }
  }

  // The programmed block under the tool (kNone: not known); those before it in pending_ the
  // tool has passed since the last sample.
  const Vec3 path = s.path_position.xyz();
  const Vec3 pos = s.position.xyz();  // disabled slots stay 0 in both
  const std::size_t j = s.line != 0 ? match(s.line, pos) : kNone;

  // Contour error: distance from the servo set-point to the path as programmed near the tool
  // (the polyline of recent on-path points when no programmed move is known).
  const std::size_t ring_n = path_ring_.size();
  path_ring_[ring_next_] = path;
  ring_next_ = ring_next_ + 1 == ring_n ? 0 : ring_next_ + 1;
  ring_size_ = std::min(ring_size_ + 1, ring_n);
  const Vec3 lag = pos - path;
  const double lag2 = dot(lag, lag);
  // The set-point on the path with a path speed from the kernel (a recorded trajectory or a
  // table run may have none).
  const bool on_path = lag2 == 0 && s.feed_mm_min > 0 && std::isfinite(s.feed_mm_min);
  // = norm(pos − path); without a post filter the set-point is on the path (0, no root).
  const double lag_mm = lag2 == 0 ? 0.0 : std::sqrt(lag2);
  summary_.max_servo_lag_mm = std::max(summary_.max_servo_lag_mm, lag_mm);
  double contour = programmed_distance(pos, j, s.t_s);
  if (std::isinf(contour)) contour = path_ring_distance(pos, lag_mm);
  summary_.max_contour_error_mm = std::max(summary_.max_contour_error_mm, contour);

  {
    // Velocity over the last cycle (at the middle of the interval) and second differences
    // a = (v_k − v_{k−1}) / (distance between interval midpoints): io/differences.hpp.
    // The accelerations only as maxima: update_deltas() leaves their divisions to
    // raise_max_quotient (|Δv / h| = |Δv| / h exactly: rounding is symmetric).
    const CycleDifferences& d = diff_.update_deltas<N>(s.t_s, s.position);
    if (d.moved) {
      const double dt = d.dt_s;
      // Every axis, without a branch: a disabled axis has vel = acc = 0 (differences.hpp), so
      // its maxima stay 0 (those from N on are not visited).
      for (std::size_t i = 0; i < N; ++i) {
        summary_.max_axis_speed_mm_min[i] =
            std::max(summary_.max_axis_speed_mm_min[i], std::fabs(d.vel[i]) * 60);
      }
      const double len = d.length_mm;
      const double speed = d.speed_mm_s;  // mm/s
      // Along the path where the set-point is on it (see the tangential acceleration below).
      const double speed_t = on_path ? s.feed_mm_min / 60 : speed;
      summary_.path_length_mm += len;
      summary_.max_feed_mm_min = std::max(summary_.max_feed_mm_min, speed * 60);
      if (d.accel) {
        const double h = d.h_s;
        for (std::size_t i = 0; i < N; ++i) {
          raise_max_quotient(summary_.max_axis_accel_mm_s2[i], std::fabs(d.dv[i]), h);
        }
        raise_max_root_quotient(summary_.max_path_accel_mm_s2, d.dv2, h);
        // Tangential: where the set-point is on the path and the kernel reports its speed
        // along it, that speed; else the chord's. A step across a corner is longer than its
        // chord, and the chord's dip read as 8 % over Amax on a bundled example
        // (cam-short-segments.ngc: 2 168 mm/s², 2 000 along the path by cncore-trajcheck).
        if (prev_on_path_ == on_path) {
          raise_max_quotient(summary_.max_tangential_accel_mm_s2,
                             std::fabs(speed_t - prev_speed_t_), h);
        } else {
          raise_max_quotient(summary_.max_tangential_accel_mm_s2, std::fabs(d.dspeed), h);
        }
      }
      // Slowest spots: time lost on each block against its programmed feed × override.
      if (j != kNone) {
        share(s, j, dt, len);
      } else if (!pending_.empty() && pending_.front().motion) {
        // On an event after the block (M2 at the end point, a waiting M code): the cycle that
        // reached it still belongs to the block.
        credit(pending_.front(), dt, len, s);
      } else if (s.line != 0) {  // a line not among the blocks: time and length only
        if (s.line != group_.line) {
          close_group();
          group_.line = s.line;
        }
        group_.time_s += dt;
        group_.length_mm += len;
      }
      prev_speed_t_ = speed_t;
      prev_on_path_ = on_path;
    }
  }
  if (j != kNone && j > 0) pass(j, s.t_s);
  prev_path_ = path;
}

void SummaryObserver::on_finish() {
  close_group();
  std::sort(top_.begin(), top_.end(),
            [](const SlowSpot& a, const SlowSpot& b) { return a.lost_s > b.lost_s; });
  summary_.slowest.clear();
  for (const SlowSpot& s : top_) {
    if (summary_.slowest.size() == kSlowReported || s.lost_s < 1e-4) break;
    summary_.slowest.push_back(s);
  }
  // Limits the machine must keep, checked on the measured trajectory (small numeric margin).
  auto& w = summary_.warnings;
  // Tables drive each axis on its own: only the per-axis limits govern them.
  const bool path_limits = summary_.mode != "table";
  const double vmax = std::max(machine_.max_feed_mm_min, machine_.rapid_mm_min);
  if (path_limits && summary_.max_feed_mm_min > vmax * 1.001 + 1e-6) {
    w.push_back(fmt::format("path speed {:.1f} mm/min exceeds the machine's {:.1f} mm/min",
                            summary_.max_feed_mm_min, vmax));
  }
  if (path_limits && summary_.max_tangential_accel_mm_s2 > machine_.max_accel_mm_s2 * 1.01 + 1e-3) {
    w.push_back(fmt::format("tangential acceleration {:.1f} mm/s² exceeds Amax {:.1f} mm/s²",
                            summary_.max_tangential_accel_mm_s2, machine_.max_accel_mm_s2));
  }
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const AxisConfig& a = machine_.axes[i];
    if (!a.enabled) continue;
    const char* u = a.rotary ? "deg" : "mm";
    if (summary_.max_axis_speed_mm_min[i] > a.max_speed_mm_min * 1.001 + 1e-6) {
      w.push_back(fmt::format("axis {} speed {:.1f} {}/min exceeds its limit {:.1f} {}/min",
                              kAxisLetters[i], summary_.max_axis_speed_mm_min[i], u,
                              a.max_speed_mm_min, u));
    }
    if (summary_.max_axis_accel_mm_s2[i] > a.max_accel_mm_s2 * 1.01 + 1e-3) {
      w.push_back(fmt::format("axis {} acceleration {:.1f} {}/s² exceeds its limit {:.1f} {}/s²",
                              kAxisLetters[i], summary_.max_axis_accel_mm_s2[i], u,
                              a.max_accel_mm_s2, u));
    }
  }
  if (path_limits && summary_.max_contour_error_mm > machine_.contour_tolerance_mm * 1.001 + 1e-9) {
    w.push_back(fmt::format("contour error {:.4f} mm exceeds the tolerance {:.4f} mm",
                            summary_.max_contour_error_mm, machine_.contour_tolerance_mm));
  }
}

std::string summary_to_json(const Summary& s, const MachineConfig& machine) {
  nlohmann::ordered_json j;
  j["cycle_time_s"] = s.cycle_time_s;
  j["blocks"] = s.blocks;
  j["path_length_mm"] = s.path_length_mm;
  j["max_feed_mm_min"] = s.max_feed_mm_min;
  j["max_tangential_accel_mm_s2"] = s.max_tangential_accel_mm_s2;
  j["max_path_accel_mm_s2"] = s.max_path_accel_mm_s2;
  nlohmann::ordered_json accel = nlohmann::ordered_json::object();
  nlohmann::ordered_json speed = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine.axes[i].enabled) continue;
    accel[axis_name(i)] = s.max_axis_accel_mm_s2[i];
    speed[axis_name(i)] = s.max_axis_speed_mm_min[i];
  }
  j["max_axis_accel_mm_s2"] = accel;
  j["max_axis_speed_mm_min"] = speed;
  j["max_contour_error_mm"] = s.max_contour_error_mm;
  j["max_servo_lag_mm"] = s.max_servo_lag_mm;
  if (!std::isnan(s.correction_min) || !std::isnan(s.time_without_correction_s)) {
    // Spec 03: time added (> 0) or saved (< 0) by the direction correction, against a second
    // run of the same program without it.
    nlohmann::ordered_json dc;
    dc["c_min"] = std::isnan(s.correction_min) ? 1.0 : s.correction_min;
    dc["c_max"] = std::isnan(s.correction_max) ? 1.0 : s.correction_max;
    if (!std::isnan(s.time_without_correction_s)) {
      dc["cycle_time_without_s"] = s.time_without_correction_s;
      dc["time_added_s"] = s.cycle_time_s - s.time_without_correction_s;
    }
    j["direction_correction"] = dc;
  }
  j["mode"] = s.mode;
  if (!s.accdec.empty()) j["accdec"] = s.accdec;
  if (s.operator_modes.dry_run_feed_mm_min > 0)
    j["dry_run_feed_mm_min"] = s.operator_modes.dry_run_feed_mm_min;
  if (s.operator_modes.single_block)
    j["single_block_wait_s"] = s.operator_modes.single_block_wait_s;
  j["cycles"] = s.cycles;
  j["period_s"] = machine.period_s;
  j["machine"] = machine.name;
  j["warnings"] = s.warnings;
  nlohmann::ordered_json spots = nlohmann::ordered_json::array();
  for (const SlowSpot& p : s.slowest) {
    nlohmann::ordered_json o;
    o["line"] = p.line;
    o["last_line"] = p.last_line != 0 ? p.last_line : p.line;
    o["lost_s"] = p.lost_s;
    o["time_s"] = p.time_s;
    o["length_mm"] = p.length_mm;
    o["average_feed_mm_min"] = p.average_feed_mm_min();
    o["programmed_feed_mm_min"] = p.programmed_feed_mm_min;
    o["visits"] = p.visits;
    o["rapid"] = p.rapid;
    spots.push_back(o);
  }
  j["slowest_spots"] = spots;
  j["time_lost_s"] = s.time_lost_s;
  j["blocks_timed"] = s.blocks_timed;
  nlohmann::ordered_json events = nlohmann::ordered_json::array();
  for (const AuxEvent& e : s.aux_events) {
    events.push_back(
        {{"t_s", e.t_s}, {"line", e.line}, {"code", fmt::format("{}{:g}", e.letter, e.value)}});
  }
  j["aux_events"] = events;
  j["aux_event_count"] = s.aux_event_count;
  if (s.load.present) {
    const LoadSummary& l = s.load;
    nlohmann::ordered_json a;
    a["adaptive"] = l.adaptive;
    a["antiwindup"] = l.antiwindup;
    a["load_source"] = l.source;
    a["target_load_pct"] = l.target_load_pct;
    a["time_without_adaptive_s"] = l.time_without_adaptive_s;
    a["time_saved_s"] = l.time_saved_s;
    a["time_above_target_s"] = l.time_above_target_s;
    a["time_above_target_plus5_s"] = l.time_above_target_band_s;
    a["peak_load_pct"] = l.peak_load_pct;
    a["mean_load_pct"] = l.mean_load_pct;
    a["m52_switches"] = l.switches;
    j["adaptive_feed"] = a;
  }
  return j.dump(2) + "\n";
}

void write_summary_json(const std::string& path, const Summary& summary,
                        const MachineConfig& machine) {
  AtomicOutputFile file(path);
  file.write(summary_to_json(summary, machine));
  file.commit();
}

std::string format_human_summary(const Summary& s, const MachineConfig& machine,
                                 const std::string& program) {
  std::string o;
  o += fmt::format("program       {}\n", program);
  std::string accdec = s.accdec.empty() ? "" : fmt::format(", {} acc/dec", s.accdec);
  if (s.operator_modes.dry_run_feed_mm_min > 0)
    accdec += fmt::format(", dry run at {:.0f} mm/min", s.operator_modes.dry_run_feed_mm_min);
  if (s.operator_modes.single_block)
    accdec += fmt::format(", single block (wait {} s)", s.operator_modes.single_block_wait_s);
  o += fmt::format("machine       {} ({} mode{}, period {} ms)\n", machine.name, s.mode, accdec,
                   machine.period_s * 1000);
  o += fmt::format("cycle time    {:.3f} s ({} cycles)\n", s.cycle_time_s, s.cycles);
  o += fmt::format("path length   {:.3f} mm in {} motion blocks\n", s.path_length_mm, s.blocks);
  o += fmt::format("max speed     {:.1f} mm/min (machine {:.0f}, rapid {:.0f})\n",
                   s.max_feed_mm_min, machine.max_feed_mm_min, machine.rapid_mm_min);
  o += fmt::format("max accel     {:.1f} mm/s² tangential, {:.1f} mm/s² resultant (Amax {:.0f})\n",
                   s.max_tangential_accel_mm_s2, s.max_path_accel_mm_s2, machine.max_accel_mm_s2);
  std::string axes;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine.axes[i].enabled) continue;
    axes += fmt::format("{}{} {:.1f}", axes.empty() ? "" : ", ", kAxisLetters[i],
                        s.max_axis_accel_mm_s2[i]);
  }
  o += fmt::format("axis accel    {} (mm/s² or deg/s²)\n", axes);
  o += fmt::format("contour error {:.4f} mm (tolerance {} mm)\n", s.max_contour_error_mm,
                   machine.contour_tolerance_mm);
  if (!std::isnan(s.time_without_correction_s)) {
    const double added = s.cycle_time_s - s.time_without_correction_s;
    o += fmt::format("correction    C {:.3f} … {:.3f}; {} {:.3f} s against {:.3f} s without it\n",
                     std::isnan(s.correction_min) ? 1.0 : s.correction_min,
                     std::isnan(s.correction_max) ? 1.0 : s.correction_max,
                     added >= 0 ? "added" : "saved", std::abs(added), s.time_without_correction_s);
  }
  if (s.slowest.empty()) {
    o += "slowest spots none (the programmed feed is kept everywhere)\n";
  } else {
    o += fmt::format(
        "slowest spots time lost against the programmed feed ({:.3f} s in all), worst first:\n",
        s.time_lost_s);
    for (const SlowSpot& p : s.slowest) {
      // A merged line (collinear pieces run as one): the source lines of its first and last piece.
      const std::string where = p.last_line != 0 && p.last_line != p.line
                                    ? fmt::format("lines {}-{}", p.line, p.last_line)
                                    : fmt::format("line {}", p.line);
      o += fmt::format("  {:<11} {:.3f} s lost of {:.3f} s, average {:.0f} of {:.0f} mm/min{}",
                       where, p.lost_s, p.time_s, p.average_feed_mm_min(), p.programmed_feed_mm_min,
                       p.rapid ? " (G0)" : "");
      if (p.visits > 1) o += fmt::format(" ({} passes)", p.visits);
      o += '\n';
    }
  }
  if (s.load.present) {
    const LoadSummary& l = s.load;
    o += fmt::format(
        "spindle load  peak {:.1f} %, mean {:.1f} %, above target {:.0f} %: {:.3f} s "
        "(+5 %: {:.3f} s); source: {}\n",
        l.peak_load_pct, l.mean_load_pct, l.target_load_pct, l.time_above_target_s,
        l.time_above_target_band_s, l.source);
    if (l.adaptive) {
      o += fmt::format("adaptive feed {} ({} M52), time saved {:.3f} s: {:.3f} s without it\n",
                       l.antiwindup, l.switches, l.time_saved_s, l.time_without_adaptive_s);
    } else {
      o += "adaptive feed off (load measured only)\n";
    }
  }
  for (const std::string& w : s.warnings) o += fmt::format("warning: {}\n", w);
  return o;
}

}  // namespace cncore::io
