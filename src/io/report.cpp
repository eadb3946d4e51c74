#include "io/report.hpp"

#include <algorithm>
#include <numbers>
#include <string_view>

#include "io/buckets.hpp"
#include "motion/piece_lines.hpp"

namespace cncore::io {

namespace {

constexpr std::size_t kSlowCandidates = 64;
constexpr std::size_t kMatchWindow = 4096;  // a cycle may pass hundreds of sub-µm pieces

double deg(double rad) {
  return rad * 180 / std::numbers::pi;
}

// Angle of an arc about its normal from start to end, counter-clockwise, in (0, 2π] (+ turns).
double arc_sweep_rad(const Block& b) {
  const Vec3 n = unit_or_zero(b.normal);
  const Vec3 rs = b.start.xyz() - b.center;
  Vec3 re = b.end.xyz() - b.center;
  re = re - dot(re, n) * n;  // remove the helix rise
  double a = std::atan2(dot(cross(rs, re), n), dot(rs, re));
  if (a <= 1e-12) a += 2 * std::numbers::pi;
  return a + 2 * std::numbers::pi * b.turns;
}

// Unit tangents (XYZ) at the start and end of a motion block; zero for a pure rotary move.
std::pair<Vec3, Vec3> tangents(const Block& b) {
  if (b.kind != BlockKind::kArc) {
    const Vec3 d = unit_or_zero(b.end.xyz() - b.start.xyz());
    return {d, d};
  }
  const Vec3 n = unit_or_zero(b.normal);
  Vec3 re = b.end.xyz() - b.center;
  re = re - dot(re, n) * n;
  // Counter-clockwise about n: the tangent is n × r.
  return {unit_or_zero(cross(n, b.start.xyz() - b.center)), unit_or_zero(cross(n, re))};
}

void merge_min(double& a, double b) {
  if (std::isnan(a) || b < a) a = b;
}
void merge_max(double& a, double b) {
  if (std::isnan(a) || b > a) a = b;
}

}  // namespace

ReportObserver::ReportObserver(const MachineConfig& machine, std::string mode,
                               ReportOptions options, SummaryObserver* accounting)
    : machine_(machine),
      mode_(std::move(mode)),
      options_(options),
      accounting_(accounting),
      diff_(machine) {
  if (accounting_ == nullptr) own_accounting_ = std::make_unique<SummaryObserver>(machine, mode_);
  options_.buckets = std::max<std::size_t>(options_.buckets, 16);
  options_.path_points = std::max<std::size_t>(options_.path_points, 64);
  buckets_.reserve(2 * options_.buckets);
  path_.reserve(options_.path_points);
  top_.reserve(kSlowCandidates);
  top_rapid_.reserve(kSlowCandidates);
  pending_max_ =
      static_cast<std::size_t>(machine.lookahead_blocks) + motion::PieceLines::kCapacity + 1024;
  // A point closer than the spacing is still kept when the speed changed by 2 % of the fastest
  // move: the colours of the top view show every slow-down.
  path_dv_mm_min_ = 0.02 * std::max(machine.max_feed_mm_min, machine.rapid_mm_min);
}

void ReportObserver::on_block(const Block& b) {
  // Set here, not in the constructor: the observer may have been moved since.
  accounting().set_share_listener(this);
  if (own_accounting_) own_accounting_->on_block(b);
  if (b.pieces > 0) return;  // a merged line: its programmed pieces follow, the samples name them
  const bool motion = is_motion(b);
  if (!motion) {
    if (b.kind == BlockKind::kDwell || (b.kind == BlockKind::kAux && b.aux_waits)) {
      for (std::deque<Pending>* q : {&pending_, &explain_pending_}) {
        if (!q->empty() && !q->back().stop_after) {
          q->back().stop_after = true;
          q->back().stop_reason = b.kind == BlockKind::kDwell
                                      ? "stop for the dwell (G4) that follows"
                                      : "stop for the waiting M code that follows";
        }
      }
      stop_pending_ = true;
    }
    return;
  }
  Pending p;
  p.line = b.line;
  p.last_line = b.last_line;
  p.kind = b.kind;
  p.cap_mm_min = b.kind == BlockKind::kRapid ? machine_.rapid_mm_min : machine_.max_feed_mm_min;
  p.feed_mm_min = b.kind == BlockKind::kRapid ? machine_.rapid_mm_min : b.feed_mm_min;
  if (b.kind == BlockKind::kArc) {
    const Vec3 n = unit_or_zero(b.normal);
    const Vec3 r = b.start.xyz() - b.center;
    p.radius_mm = norm(r - dot(r, n) * n);
    const double rise = dot(b.end.xyz() - b.start.xyz(), n);
    const double along = p.radius_mm * arc_sweep_rad(b);
    p.length_mm = std::sqrt(along * along + rise * rise);
    p.arc_limit_mm_min = std::sqrt(machine_.max_accel_mm_s2 * p.radius_mm) * 60;
  } else {
    p.length_mm = norm(b.end.xyz() - b.start.xyz());
  }
  const auto [t_start, t_end] = tangents(b);
  const bool has_dir = norm(t_start) > 0.5;
  p.stop_before = stop_pending_ || mode_ == "stop";
  p.stop_after = b.path_mode == PathMode::kExactStop || mode_ == "stop";
  if (p.stop_after) {
    p.stop_reason = mode_ == "stop" ? "stop at every block (stop mode)" : "exact stop (G61.1/G9)";
  }
  if (has_dir && have_tangent_ && !p.stop_before) {
    const double c = std::clamp(dot(last_tangent_, t_start), -1.0, 1.0);
    p.entry_corner_deg = deg(std::acos(c));
  }
  p.move = ProgrammedMove(b);
  if (has_dir) {
    last_tangent_ = t_end;
    have_tangent_ = true;
  }
  stop_pending_ = false;
  push_block(pending_, p);
  push_block(explain_pending_, p);
}

void ReportObserver::push_block(std::deque<Pending>& pending, Pending p) {
  if (!pending.empty()) {
    Pending& prev = pending.back();
    prev.has_successor = true;
    prev.exit_corner_deg = p.entry_corner_deg;
    if (!prev.stop_after && p.stop_before) {
      prev.stop_after = true;
      prev.stop_reason = "stop before the next move";
    }
    // The limits behind: carried on from the previous block, or the previous block itself.
    const bool corner = p.entry_corner_deg >= kCornerDeg;
    p.from_stop_mm = p.stop_before ? 0 : prev.from_stop_mm + prev.length_mm;
    p.from_corner_mm = corner ? 0 : prev.from_corner_mm + prev.length_mm;
    if (prev.arc_limit_mm_min > 0) {
      p.from_arc_mm = 0;
      p.from_arc_limit_mm_min = prev.arc_limit_mm_min;
    } else {
      p.from_arc_mm = prev.from_arc_mm + prev.length_mm;
      p.from_arc_limit_mm_min = prev.from_arc_limit_mm_min;
    }
    if (p.stop_before) p.from_corner_mm = p.from_arc_mm = INFINITY;
  }
  pending.push_back(p);
  // Never more than the kernel's buffer and its ring of pieces (as the summary); if lines never
  // match, forget the oldest.
  while (pending.size() > pending_max_) pending.pop_front();
}

ReportObserver::Pending* ReportObserver::current_block(std::deque<Pending>& pending,
                                                       std::uint32_t line) {
  const std::size_t n = std::min(pending.size(), kMatchWindow);
  for (std::size_t j = 0; j < n; ++j) {
    if (pending[j].line == line) {
      pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(j));
      return &pending.front();
    }
  }
  return nullptr;
}

void ReportObserver::add_to_bucket(const ReportBucket& s) {
  auto merge = [](ReportBucket& a, const ReportBucket& b) {
    // Drawing order of a's and b's extremes: the earlier one first.
    const bool speed_min_first =
        b.speed_min_mm_min < a.speed_min_mm_min
            ? (b.speed_max_mm_min > a.speed_max_mm_min ? b.speed_min_first : false)
            : (b.speed_max_mm_min > a.speed_max_mm_min ? true : a.speed_min_first);
    const bool accel_min_first =
        b.accel_min_mm_s2 < a.accel_min_mm_s2
            ? (b.accel_max_mm_s2 > a.accel_max_mm_s2 ? b.accel_min_first : false)
            : (b.accel_max_mm_s2 > a.accel_max_mm_s2 ? true : a.accel_min_first);
    a.speed_min_first = speed_min_first;
    a.accel_min_first = accel_min_first;
    a.t_last_s = b.t_last_s;
    a.samples += b.samples;
    a.speed_min_mm_min = std::min(a.speed_min_mm_min, b.speed_min_mm_min);
    a.speed_max_mm_min = std::max(a.speed_max_mm_min, b.speed_max_mm_min);
    a.accel_min_mm_s2 = std::min(a.accel_min_mm_s2, b.accel_min_mm_s2);
    a.accel_max_mm_s2 = std::max(a.accel_max_mm_s2, b.accel_max_mm_s2);
    a.path_accel_max_mm_s2 = std::max(a.path_accel_max_mm_s2, b.path_accel_max_mm_s2);
    a.feed_max_mm_min = std::max(a.feed_max_mm_min, b.feed_max_mm_min);
    a.limit_max_mm_min = std::max(a.limit_max_mm_min, b.limit_max_mm_min);
    a.override_min_pct = std::min(a.override_min_pct, b.override_min_pct);
    a.override_max_pct = std::max(a.override_max_pct, b.override_max_pct);
    if (!std::isnan(b.correction_min)) merge_min(a.correction_min, b.correction_min);
    if (!std::isnan(b.correction_max)) merge_max(a.correction_max, b.correction_max);
    if (!std::isnan(b.load_max_pct)) merge_max(a.load_max_pct, b.load_max_pct);
    if (!std::isnan(b.load_target_pct)) a.load_target_pct = b.load_target_pct;
  };
  add_to_buckets(buckets_, bucket_samples_, options_.buckets, s, merge);
}

void ReportObserver::add_path_point(const ReportPathPoint& p) {
  if (!path_.empty()) {
    const ReportPathPoint& last = path_.back();
    const double dx = p.x_mm - last.x_mm, dy = p.y_mm - last.y_mm, dz = p.z_mm - last.z_mm;
    const bool far = dx * dx + dy * dy + dz * dz >= path_step_mm_ * path_step_mm_;
    const bool changed =
        std::fabs(p.speed_mm_min - last.speed_mm_min) >= path_dv_mm_min_ || p.rapid != last.rapid;
    if (!far && !changed) return;
  }
  if (path_.size() == options_.path_points) thin_path();
  path_.push_back(p);
}

// Full: double the spacing and the speed step, and keep only the points that the new rule
// keeps (the first point always). Repeats until at most 3/4 of the points remain.
void ReportObserver::thin_path() {
  do {
    path_step_mm_ *= 2;
    path_dv_mm_min_ *= 1.5;
    std::size_t kept = 1;
    for (std::size_t i = 1; i < path_.size(); ++i) {
      const ReportPathPoint& last = path_[kept - 1];
      const double dx = path_[i].x_mm - last.x_mm, dy = path_[i].y_mm - last.y_mm;
      const double dz = path_[i].z_mm - last.z_mm;
      const bool far = dx * dx + dy * dy + dz * dz >= path_step_mm_ * path_step_mm_;
      const bool changed =
          std::fabs(path_[i].speed_mm_min - last.speed_mm_min) >= path_dv_mm_min_ ||
          path_[i].rapid != last.rapid;
      if (far || changed || i + 1 == path_.size()) path_[kept++] = path_[i];
    }
    path_.resize(kept);
  } while (path_.size() > options_.path_points * 3 / 4);
}

void ReportObserver::on_sample(const motion::Sample& s) {
  if (own_accounting_) own_accounting_->on_sample(s);
  ++samples_;
  has_override_ = has_override_ || s.override_pct != 100;
  has_correction_ = has_correction_ || !std::isnan(s.correction);
  has_load_ = has_load_ || !std::isnan(s.load_pct);

  // Finite differences as in the summary (io/differences.hpp); 0 until known.
  const CycleDifferences& d = diff_.update(s.t_s, s.position);
  const double speed = d.moved ? d.speed_mm_s : 0;  // mm/s
  const double accel = d.accel ? d.tangential_accel_mm_s2 : 0;
  const double path_accel = d.accel ? d.path_accel_mm_s2 : 0;
  const double speed_mm_min = speed * 60;

  const Pending* b = s.line != 0 ? current_block(pending_, s.line) : nullptr;
  const bool rapid = b != nullptr && b->kind == BlockKind::kRapid;
  if (b != nullptr && !rapid) cutting_vmax_mm_min_ = std::max(cutting_vmax_mm_min_, speed_mm_min);

  ReportBucket one;
  one.t_first_s = one.t_last_s = s.t_s;
  one.samples = 1;
  one.speed_min_mm_min = one.speed_max_mm_min = speed_mm_min;
  one.accel_min_mm_s2 = one.accel_max_mm_s2 = accel;
  one.path_accel_max_mm_s2 = path_accel;
  one.feed_max_mm_min = b ? b->feed_mm_min : 0;
  one.limit_max_mm_min = b ? b->cap_mm_min : 0;
  one.override_min_pct = one.override_max_pct = s.override_pct;
  one.correction_min = one.correction_max = s.correction;
  one.load_max_pct = s.load_pct;
  one.load_target_pct = s.load_target_pct;
  add_to_bucket(one);
  add_path_point(
      {s.position[0], s.position[1], s.position[2], static_cast<float>(speed_mm_min), rapid});
}

void ReportObserver::on_finish() {
  if (own_accounting_) own_accounting_->on_finish();
  // The last block has no successor: it ends at a stop.
  if (!explain_pending_.empty() && !explain_pending_.front().has_successor) {
    explain_pending_.front().stop_after = true;
  }
  close_group();
}

std::size_t ReportObserver::memory_bytes() const {
  std::size_t n = buckets_.capacity() * sizeof(ReportBucket) +
                  path_.capacity() * sizeof(ReportPathPoint) +
                  (pending_.size() + explain_pending_.size()) * sizeof(Pending) +
                  (top_.capacity() + top_rapid_.capacity()) * sizeof(ReportSlowSpot);
  for (const ReportSlowSpot& s : top_) n += s.why.capacity();
  for (const ReportSlowSpot& s : top_rapid_) n += s.why.capacity();
  return n;
}

}  // namespace cncore::io
