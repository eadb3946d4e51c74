#include "io/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <numbers>
#include <string_view>

#include "io/buckets.hpp"
#include "io/report_page.hpp"

namespace cncore::io {

namespace {

constexpr std::size_t kSlowCandidates = 64;
constexpr std::size_t kMatchWindow = 4096;  // a cycle may pass hundreds of sub-µm pieces

double deg(double rad) {
  return rad * 180 / std::numbers::pi;
}

Vec3 unit(Vec3 v) {
  const double n = norm(v);
  return n > 0 ? (1 / n) * v : Vec3{};
}

// Angle of an arc about its normal from start to end, counter-clockwise, in (0, 2π] (+ turns).
double arc_sweep_rad(const Block& b) {
  const Vec3 n = unit(b.normal);
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
    const Vec3 d = unit(b.end.xyz() - b.start.xyz());
    return {d, d};
  }
  const Vec3 n = unit(b.normal);
  Vec3 re = b.end.xyz() - b.center;
  re = re - dot(re, n) * n;
  // Counter-clockwise about n: the tangent is n × r.
  return {unit(cross(n, b.start.xyz() - b.center)), unit(cross(n, re))};
}

using page::html_escape;
using page::js_array;

void merge_min(double& a, double b) {
  if (std::isnan(a) || b < a) a = b;
}
void merge_max(double& a, double b) {
  if (std::isnan(a) || b > a) a = b;
}

}  // namespace

ReportObserver::ReportObserver(const MachineConfig& machine, std::string mode,
                               ReportOptions options)
    : machine_(machine), mode_(std::move(mode)), options_(options), diff_(machine) {
  options_.buckets = std::max<std::size_t>(options_.buckets, 16);
  options_.path_points = std::max<std::size_t>(options_.path_points, 64);
  buckets_.reserve(2 * options_.buckets);
  path_.reserve(options_.path_points);
  top_.reserve(kSlowCandidates);
  // A point closer than the spacing is still kept when the speed changed by 2 % of the fastest
  // move: the colours of the top view show every slow-down.
  path_dv_mm_min_ = 0.02 * std::max(machine.max_feed_mm_min, machine.rapid_mm_min);
}

void ReportObserver::on_block(const Block& b) {
  if (b.pieces > 0) return;  // a merged line: its programmed pieces follow, the samples name them
  const bool motion = is_motion(b);
  if (!motion) {
    if (b.kind == BlockKind::kDwell || (b.kind == BlockKind::kAux && b.aux_waits)) {
      if (!pending_.empty() && !pending_.back().stop_after) {
        pending_.back().stop_after = true;
        pending_.back().stop_reason = b.kind == BlockKind::kDwell
                                          ? "stop for the dwell (G4) that follows"
                                          : "stop for the waiting M code that follows";
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
    const Vec3 n = unit(b.normal);
    const Vec3 r = b.start.xyz() - b.center;
    p.radius_mm = norm(r - dot(r, n) * n);
    const double rise = dot(b.end.xyz() - b.start.xyz(), n);
    const double along = p.radius_mm * arc_sweep_rad(b);
    p.length_mm = std::sqrt(along * along + rise * rise);
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
  if (!pending_.empty()) {
    Pending& prev = pending_.back();
    prev.has_successor = true;
    prev.exit_corner_deg = p.entry_corner_deg;
    if (!prev.stop_after && p.stop_before) {
      prev.stop_after = true;
      prev.stop_reason = "stop before the next move";
    }
  }
  if (has_dir) {
    last_tangent_ = t_end;
    have_tangent_ = true;
  }
  stop_pending_ = false;
  pending_.push_back(p);
  // Never more than the kernel's buffer; if lines never match, forget the oldest.
  while (pending_.size() > static_cast<std::size_t>(machine_.lookahead_blocks) + 1024) {
    pending_.pop_front();
  }
}

const ReportObserver::Pending* ReportObserver::current_block(std::uint32_t line) {
  const std::size_t n = std::min(pending_.size(), kMatchWindow);
  for (std::size_t j = 0; j < n; ++j) {
    if (pending_[j].line == line) {
      pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(j));
      return &pending_.front();
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
    const double dx = p.x_mm - last.x_mm, dy = p.y_mm - last.y_mm;
    const bool far = dx * dx + dy * dy >= path_step_mm_ * path_step_mm_;
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
      const bool far = dx * dx + dy * dy >= path_step_mm_ * path_step_mm_;
      const bool changed =
          std::fabs(path_[i].speed_mm_min - last.speed_mm_min) >= path_dv_mm_min_ ||
          path_[i].rapid != last.rapid;
      if (far || changed || i + 1 == path_.size()) path_[kept++] = path_[i];
    }
    path_.resize(kept);
  } while (path_.size() > options_.path_points * 3 / 4);
}

void ReportObserver::on_sample(const motion::Sample& s) {
  ++samples_;
  has_override_ = has_override_ || s.override_pct != 100;
  has_correction_ = has_correction_ || !std::isnan(s.correction);
  has_load_ = has_load_ || !std::isnan(s.load_pct);

  // Finite differences as in the summary (io/differences.hpp); 0 until known.
  const double dt = have_prev_ ? s.t_s - prev_t_ : 0.0;
  const CycleDifferences& d = diff_.update(s.t_s, s.position);
  const double speed = d.moved ? d.speed_mm_s : 0;  // mm/s
  const double len = d.moved ? d.length_mm : 0;
  const double accel = d.accel ? d.tangential_accel_mm_s2 : 0;
  const double path_accel = d.accel ? d.path_accel_mm_s2 : 0;
  prev_t_ = s.t_s;
  have_prev_ = true;
  const double speed_mm_min = speed * 60;

  // The block executing: close the previous line's group first (its block is still at the front
  // of pending_), then look up the new one.
  if (s.line != group_.spot.line || !group_.active) {
    close_group();
    group_.active = true;
    group_.spot = ReportSlowSpot{};
    group_.spot.line = s.line;
    group_.spot.min_speed_mm_min = INFINITY;
    group_.t_start_s = prev_t_ - dt;
    group_.first_speed_mm_min = -1;
    group_.last_speed_mm_min = 0;
  }
  const Pending* b = s.line != 0 ? current_block(s.line) : nullptr;
  if (b != nullptr) group_.spot.last_line = b->last_line;
  const double feed = b ? b->feed_mm_min : 0;
  const double cap = b ? b->cap_mm_min : 0;
  const double target = b ? std::min(b->feed_mm_min * s.override_pct / 100, b->cap_mm_min) : 0;

  ReportBucket one;
  one.t_first_s = one.t_last_s = s.t_s;
  one.samples = 1;
  one.speed_min_mm_min = one.speed_max_mm_min = speed_mm_min;
  one.accel_min_mm_s2 = one.accel_max_mm_s2 = accel;
  one.path_accel_max_mm_s2 = path_accel;
  one.feed_max_mm_min = feed;
  one.limit_max_mm_min = cap;
  one.override_min_pct = one.override_max_pct = s.override_pct;
  one.correction_min = one.correction_max = s.correction;
  one.load_max_pct = s.load_pct;
  one.load_target_pct = s.load_target_pct;
  add_to_bucket(one);
  add_path_point({s.position[0], s.position[1], static_cast<float>(speed_mm_min),
                  b != nullptr && b->kind == BlockKind::kRapid});

  if (s.line != 0 && dt > 0) {
    ReportSlowSpot& g = group_.spot;
    g.time_s += dt;
    g.length_mm += len;
    if (group_.first_speed_mm_min < 0) group_.first_speed_mm_min = speed_mm_min;
    group_.last_speed_mm_min = speed_mm_min;
    if (target > 0 && speed_mm_min < target) g.lost_s += dt * (1 - speed_mm_min / target);
    // The slowest cycle of the visit, measured against what was asked there.
    const double ratio = target > 0 ? speed_mm_min / target : 1;
    const double best = g.target_mm_min > 0 ? g.min_speed_mm_min / g.target_mm_min : INFINITY;
    if (ratio < best) {
      g.min_speed_mm_min = speed_mm_min;
      g.target_mm_min = target;
      g.t_min_s = s.t_s;
      g.x_mm = s.position[0];
      g.y_mm = s.position[1];
      g.override_pct = s.override_pct;
      g.correction = s.correction;
      g.load_pct = s.load_pct;
      g.load_target_pct = s.load_target_pct;
    }
  }
}

// Why the line is slow at its slowest cycle, from what is known about the block there. The
// reasons are checked against the limit each one sets (A = machine acceleration):
//  arc of radius R: v ≤ √(A·R) (normal acceleration v²/R ≤ A);
//  a block of length L started or ended at rest cannot exceed √(A·L) (accelerate over L/2,
//  brake over L/2: v² = 2·A·L/2);
//  a corner or a stop is found where the minimum lies: near the start → the entry, near the
//  end → the exit.
std::string ReportObserver::explain(const ReportSlowSpot& s, const Pending* b, double fraction,
                                    bool start_stopped, bool end_stopped) const {
  std::vector<std::string> why;
  const double a = machine_.max_accel_mm_s2;
  const double f = b ? std::min(b->feed_mm_min, b->cap_mm_min) : s.target_mm_min;
  if (s.override_pct < 99.95) why.push_back(fmt::format("feed override {:.0f} %", s.override_pct));
  if (!std::isnan(s.correction) && s.correction < 0.999) {
    why.push_back(fmt::format("direction correction ×{:.3g}", s.correction));
  }
  if (!std::isnan(s.load_pct) && !std::isnan(s.load_target_pct) &&
      s.load_pct >= 0.95 * s.load_target_pct) {
    why.push_back(
        fmt::format("cutting load {:.0f} % (target {:.0f} %)", s.load_pct, s.load_target_pct));
  }
  if (b != nullptr) {
    // The entry and the exit of the block: each counts when the minimum lies there or the
    // line starts / ends at standstill; the one nearer the minimum is named first.
    std::vector<std::string> entry, exit;
    if (fraction <= 0.35 || start_stopped) {
      if (b->stop_before && start_stopped) {
        entry.emplace_back("start from standstill");
      } else if (b->entry_corner_deg >= 1) {
        entry.push_back(fmt::format("corner {:.0f}° from the previous line", b->entry_corner_deg));
      }
    }
    if (fraction >= 0.65 || end_stopped) {
      if (b->stop_after && end_stopped) {
        exit.emplace_back(b->has_successor ? b->stop_reason : "stop at the end of the program");
      } else if (b->exit_corner_deg >= 1) {
        exit.push_back(fmt::format("corner {:.0f}° into the next line", b->exit_corner_deg));
      }
    }
    if (fraction >= 0.5) std::swap(entry, exit);
    why.insert(why.end(), entry.begin(), entry.end());
    why.insert(why.end(), exit.begin(), exit.end());
    if (b->kind == BlockKind::kArc && b->radius_mm > 0) {
      const double cap = std::sqrt(a * b->radius_mm) * 60;
      if (cap < 0.99 * f) {
        why.push_back(
            fmt::format("arc R {:.4g} mm: v ≤ √(A·R) = {:.0f} mm/min", b->radius_mm, cap));
      }
    }
    const double reach = std::sqrt(a * b->length_mm) * 60;
    if (reach < 0.99 * f) {
      why.push_back(
          fmt::format("short segment {:.3g} mm: too short to reach F{:.0f} (≤ {:.0f} "
                      "mm/min between stops)",
                      b->length_mm, f, reach));
    }
  }
  if (why.empty()) why.emplace_back("acceleration ramp");
  std::string o;
  for (const std::string& w : why) o += (o.empty() ? "" : "; ") + w;
  return o;
}

void ReportObserver::close_group() {
  if (!group_.active) return;
  group_.active = false;
  ReportSlowSpot g = group_.spot;
  if (g.line == 0 || g.time_s <= 0 || !std::isfinite(g.min_speed_mm_min)) return;
  const Pending* b =
      !pending_.empty() && pending_.front().line == g.line ? &pending_.front() : nullptr;
  const double span = prev_t_ - group_.t_start_s;
  const double fraction = span > 0 ? (g.t_min_s - group_.t_start_s) / span : 0;
  // At standstill: below 2 % of the asked speed, or within one cycle's speed change of 0 — a
  // sampled stop lands with a last step of up to Amax·τ (the acceleration type does).
  const double one_cycle_mm_min = machine_.max_accel_mm_s2 * machine_.period_s * 60.0 * 1.001;
  const double still = std::max(0.02 * std::max(g.target_mm_min, 1.0), one_cycle_mm_min);
  const bool start_stopped = group_.first_speed_mm_min < still;
  const bool end_stopped = group_.last_speed_mm_min < still;
  g.visits = 1;
  auto same = std::find_if(top_.begin(), top_.end(),
                           [&](const ReportSlowSpot& s) { return s.line == g.line; });
  if (same != top_.end()) {
    // Another visit of the line (loop, subroutine): add up, keep the slowest visit's details.
    const double r_old = same->target_mm_min > 0 ? same->min_speed_mm_min / same->target_mm_min : 1;
    const double r_new = g.target_mm_min > 0 ? g.min_speed_mm_min / g.target_mm_min : 1;
    ReportSlowSpot merged = r_new < r_old ? g : *same;
    if (r_new < r_old) merged.why = explain(g, b, fraction, start_stopped, end_stopped);
    merged.lost_s = same->lost_s + g.lost_s;
    merged.time_s = same->time_s + g.time_s;
    merged.length_mm = same->length_mm + g.length_mm;
    merged.visits = same->visits + 1;
    *same = merged;
    return;
  }
  if (g.lost_s <= 0) return;
  g.why = explain(g, b, fraction, start_stopped, end_stopped);
  if (top_.size() < kSlowCandidates) {
    top_.push_back(g);
    return;
  }
  auto least = std::min_element(top_.begin(), top_.end(),
                                [](const auto& x, const auto& y) { return x.lost_s < y.lost_s; });
  if (g.lost_s > least->lost_s) *least = g;
}

void ReportObserver::on_finish() {
  // The last block has no successor: it ends at a stop.
  if (!pending_.empty() && !pending_.front().has_successor) pending_.front().stop_after = true;
  close_group();
}

std::vector<ReportSlowSpot> ReportObserver::slowest() const {
  std::vector<ReportSlowSpot> v = top_;
  std::sort(v.begin(), v.end(), [](const auto& x, const auto& y) {
    return x.lost_s != y.lost_s ? x.lost_s > y.lost_s : x.line < y.line;
  });
  if (v.size() > options_.slow_spots) v.resize(options_.slow_spots);
  return v;
}

std::size_t ReportObserver::memory_bytes() const {
  std::size_t n = buckets_.capacity() * sizeof(ReportBucket) +
                  path_.capacity() * sizeof(ReportPathPoint) + pending_.size() * sizeof(Pending) +
                  top_.capacity() * sizeof(ReportSlowSpot);
  for (const ReportSlowSpot& s : top_) n += s.why.capacity();
  return n;
}

// ---------------------------------------------------------------------------------------------

namespace {

// Texts of the wanted program lines (1-based), read once, streaming.
std::map<std::uint32_t, std::string> program_lines(const std::string& path,
                                                   const std::vector<std::uint32_t>& wanted) {
  std::map<std::uint32_t, std::string> out;
  if (wanted.empty()) return out;
  const std::uint32_t last = *std::max_element(wanted.begin(), wanted.end());
  std::ifstream in(path, std::ios::binary);
  std::string text;
  for (std::uint32_t n = 1; n <= last && std::getline(in, text); ++n) {
    if (std::find(wanted.begin(), wanted.end(), n) == wanted.end()) continue;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.size() > 160) text = text.substr(0, 157) + "...";
    out[n] = text;
  }
  return out;
}

// The page script: charts with uPlot, the top view on a canvas. Errors are caught and shown
// on the page (and recorded in #cncore-status for the browser test).
constexpr std::string_view kPageScript = R"JS(
(function () {
  const D = window.CNCORE_DATA;
  const { fmt, width, chart } = window.cncore;
  const T = D.t;
  chart('speed-chart', 'Path speed', [
    { label: 't (s)', value: (u, v) => fmt(v, 3) },
    { label: 'speed (mm/min)', stroke: '#1f77b4', width: 1.5, value: (u, v) => fmt(v, 0) },
    { label: 'programmed feed (mm/min)', stroke: '#2ca02c', width: 1, dash: [6, 3], value: (u, v) => fmt(v, 0) },
    { label: 'machine limit (mm/min)', stroke: '#d62728', width: 1, dash: [2, 3], value: (u, v) => fmt(v, 0) },
    { label: 'override (%)', stroke: '#9467bd', width: 1, scale: 'pct', value: (u, v) => fmt(v, 0) },
  ], [T, D.speed, D.feed, D.limit, D.override], [
    {}, { label: 'mm/min', size: 70 }, { side: 1, scale: 'pct', label: '%', grid: { show: false } },
  ], { x: { time: false }, pct: { range: [0, Math.max(150, D.override_max * 1.1)] } });
  const A = D.accel_limit;
  chart('accel-chart', 'Acceleration', [
    { label: 't (s)', value: (u, v) => fmt(v, 3) },
    { label: 'tangential (mm/s²)', stroke: '#ff7f0e', width: 1.5, value: (u, v) => fmt(v, 0) },
    { label: 'resultant incl. normal (mm/s²)', stroke: '#8c564b', width: 1, value: (u, v) => fmt(v, 0) },
    { label: '+limit', stroke: '#d62728', dash: [2, 3], width: 1, value: (u, v) => fmt(v, 0) },
    { label: '−limit', stroke: '#d62728', dash: [2, 3], width: 1, value: (u, v) => fmt(v, 0) },
  ], [T, D.accel, D.path_accel, T.map(() => A), T.map(() => -A)], [
    {}, { label: 'mm/s²', size: 70 },
  ], { x: { time: false } });
  if (D.correction || D.load) {
    const s = [{ label: 't (s)', value: (u, v) => fmt(v, 3) }], d = [T];
    if (D.correction) { s.push({ label: 'correction (×)', stroke: '#17becf', scale: 'k', value: (u, v) => fmt(v, 3) }); d.push(D.correction); }
    if (D.load) {
      s.push({ label: 'load (%)', stroke: '#e377c2', scale: '%', value: (u, v) => fmt(v, 1) }); d.push(D.load);
      s.push({ label: 'load target (%)', stroke: '#7f7f7f', dash: [4, 4], scale: '%', value: (u, v) => fmt(v, 1) }); d.push(D.load_target);
    }
    const axes = [{}];
    if (D.correction) axes.push({ scale: 'k', label: '×', size: 60 });
    if (D.load) axes.push({ scale: '%', label: '%', side: D.correction ? 1 : 3, grid: { show: !D.correction } });
    document.getElementById('extra-section').hidden = false;
    chart('extra-chart', 'Correction and load', s, d, axes, { x: { time: false } });
  }

  // Top view: X/Y of the servo set-points, coloured by speed (blue slow → red fast); rapids grey.
  const cv = document.getElementById('path-canvas');
  const P = D.path, n = P.x.length;
  cv.width = width(); cv.height = Math.round(cv.width * 0.62);
  const ctx = cv.getContext('2d');
  ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, cv.width, cv.height);
  if (n > 0) {
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (let i = 0; i < n; i++) {
      x0 = Math.min(x0, P.x[i]); x1 = Math.max(x1, P.x[i]);
      y0 = Math.min(y0, P.y[i]); y1 = Math.max(y1, P.y[i]);
    }
    const pad = 30, w = cv.width - 2 * pad - 60, h = cv.height - 2 * pad;
    const k = Math.min(w / Math.max(x1 - x0, 1e-9), h / Math.max(y1 - y0, 1e-9));
    const X = (x) => pad + (x - x0) * k, Y = (y) => cv.height - pad - (y - y0) * k;
    const vmax = Math.max(D.vmax, 1);
    const colour = (v) => 'hsl(' + Math.round(240 * (1 - Math.min(v / vmax, 1))) + ',85%,45%)';
    ctx.lineWidth = 1.5; ctx.lineCap = 'round';
    for (let i = 1; i < n; i++) {
      ctx.beginPath();
      ctx.strokeStyle = P.rapid[i] ? '#bbb' : colour(P.v[i]);
      ctx.setLineDash(P.rapid[i] ? [4, 3] : []);
      ctx.moveTo(X(P.x[i - 1]), Y(P.y[i - 1])); ctx.lineTo(X(P.x[i]), Y(P.y[i]));
      ctx.stroke();
    }
    ctx.setLineDash([]);
    ctx.font = '12px sans-serif';
    D.slow.forEach((s, i) => {
      ctx.beginPath(); ctx.strokeStyle = '#000'; ctx.arc(X(s.x), Y(s.y), 6, 0, 2 * Math.PI); ctx.stroke();
      ctx.fillStyle = '#000'; ctx.fillText(String(i + 1), X(s.x) + 8, Y(s.y) - 6);
    });
    // Colour bar.
    const bx = cv.width - 50;
    for (let j = 0; j < h; j++) { ctx.fillStyle = colour(vmax * (1 - j / h)); ctx.fillRect(bx, pad + j, 14, 1); }
    ctx.fillStyle = '#000';
    ctx.fillText(Math.round(vmax) + '', bx - 4, pad - 6);
    ctx.fillText('0 mm/min', bx - 20, pad + h + 14);
    ctx.fillText('X ' + x0.toFixed(1) + ' … ' + x1.toFixed(1) + ' mm,  Y ' + y0.toFixed(1) + ' … ' + y1.toFixed(1) + ' mm', pad, cv.height - 8);
  }

  // For the browser test (uPlot draws in a later task).
  setTimeout(window.cncore.check, 50);
})();
)JS";

constexpr std::string_view kStyle = R"CSS(
body { font: 14px/1.4 system-ui, sans-serif; margin: 20px; color: #222; max-width: 1160px; }
h1 { font-size: 20px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 22px 0 6px; }
table { border-collapse: collapse; } td, th { padding: 2px 10px 2px 0; text-align: left; vertical-align: top; }
table.slow td, table.slow th { border-bottom: 1px solid #ddd; padding: 3px 8px; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
code { background: #f4f4f4; padding: 0 3px; } table.slow code { white-space: pre; }
.warn { color: #a40; } #cncore-status { color: #c00; font-weight: bold; }
.note { color: #666; font-size: 12px; }
)CSS";

}  // namespace

std::string render_report_html(const ReportObserver& report, const Summary& summary,
                               const MachineConfig& machine, const ReportInput& input) {
  const std::string title =
      input.title.empty() ? "cncore report: " + page::basename_of(input.program) : input.title;
  const auto& bk = report.buckets();
  const std::vector<ReportSlowSpot> slow = report.slowest();

  // Time series: two points per bucket (its minimum and maximum, in the order they came), so the
  // extremes of every bucket are drawn.
  const std::size_t n = bk.size() * 2;
  auto at_t = [&](std::size_t i) {
    const ReportBucket& b = bk[i / 2];
    return i % 2 == 0 ? b.t_first_s : std::max(b.t_last_s, b.t_first_s);
  };
  auto ordered = [&](std::size_t i, double lo, double hi, bool lo_first) {
    return (i % 2 == 0) == lo_first ? lo : hi;
  };
  double override_max = 100, vmax = 0;
  for (const ReportBucket& b : bk) {
    override_max = std::max(override_max, b.override_max_pct);
    vmax = std::max(vmax, b.speed_max_mm_min);
  }
  std::string data = "window.CNCORE_DATA={";
  data += "\"t\":" + js_array(n, at_t);
  data += ",\"speed\":" + js_array(n, [&](std::size_t i) {
            const ReportBucket& b = bk[i / 2];
            return ordered(i, b.speed_min_mm_min, b.speed_max_mm_min, b.speed_min_first);
          });
  data += ",\"accel\":" + js_array(n, [&](std::size_t i) {
            const ReportBucket& b = bk[i / 2];
            return ordered(i, b.accel_min_mm_s2, b.accel_max_mm_s2, b.accel_min_first);
          });
  data += ",\"path_accel\":" +
          js_array(n, [&](std::size_t i) { return bk[i / 2].path_accel_max_mm_s2; });
  data += ",\"feed\":" + js_array(n, [&](std::size_t i) {
            const double f = bk[i / 2].feed_max_mm_min;
            return f > 0 ? f : NAN;
          });
  data += ",\"limit\":" + js_array(n, [&](std::size_t i) {
            const double f = bk[i / 2].limit_max_mm_min;
            return f > 0 ? f : NAN;
          });
  data += ",\"override\":" + js_array(n, [&](std::size_t i) {
            const ReportBucket& b = bk[i / 2];
            return i % 2 == 0 ? b.override_min_pct : b.override_max_pct;
          });
  if (report.has_correction()) {
    data += ",\"correction\":" + js_array(n, [&](std::size_t i) {
              const ReportBucket& b = bk[i / 2];
              return i % 2 == 0 ? b.correction_min : b.correction_max;
            });
  } else {
    data += ",\"correction\":null";
  }
  if (report.has_load()) {
    data += ",\"load\":" + js_array(n, [&](std::size_t i) { return bk[i / 2].load_max_pct; });
    data +=
        ",\"load_target\":" + js_array(n, [&](std::size_t i) { return bk[i / 2].load_target_pct; });
  } else {
    data += ",\"load\":null";
  }
  data += fmt::format(",\"accel_limit\":{},\"override_max\":{},\"vmax\":{}",
                      machine.max_accel_mm_s2, override_max, vmax);
  const auto& p = report.path();
  data += ",\"path\":{\"x\":" + js_array(p.size(), [&](std::size_t i) { return p[i].x_mm; });
  data += ",\"y\":" + js_array(p.size(), [&](std::size_t i) { return p[i].y_mm; });
  data += ",\"v\":" + js_array(p.size(), [&](std::size_t i) { return double{p[i].speed_mm_min}; });
  data += ",\"rapid\":" + js_array(p.size(), [&](std::size_t i) { return p[i].rapid ? 1.0 : 0.0; });
  data += "},\"slow\":[";
  for (std::size_t i = 0; i < slow.size(); ++i) {
    data += fmt::format("{}{{\"x\":{:.6g},\"y\":{:.6g},\"line\":{}}}", i ? "," : "", slow[i].x_mm,
                        slow[i].y_mm, slow[i].line);
  }
  data += "]};";

  std::vector<std::uint32_t> lines;
  for (const ReportSlowSpot& s : slow) lines.push_back(s.line);
  const auto texts = program_lines(input.program, lines);

  std::string o;
  o.reserve(data.size() + 120000);
  o += page::head(title, kStyle);
  o += "<h1 id=\"title\">" + html_escape(title) + "</h1>\n";
  o += fmt::format("<div class=\"note\">program <code>{}</code>, machine {}</div>\n",
                   html_escape(input.program), html_escape(machine.name));
  o += page::kStatusDiv;

  o += "<h2>Summary</h2>\n<table id=\"summary\">\n";
  auto row = [&](const char* key, const std::string& label, double value, const std::string& text) {
    o += fmt::format("<tr><th>{}</th><td id=\"s-{}\" data-value=\"{:.9g}\">{}</td></tr>\n", label,
                     key, value, text);
  };
  row("cycle_time_s", "cycle time", summary.cycle_time_s,
      fmt::format("{:.3f} s", summary.cycle_time_s));
  row("cycles", "cycles", static_cast<double>(summary.cycles), fmt::format("{}", summary.cycles));
  row("blocks", "motion blocks", static_cast<double>(summary.blocks),
      fmt::format("{}", summary.blocks));
  row("path_length_mm", "path length", summary.path_length_mm,
      fmt::format("{:.3f} mm", summary.path_length_mm));
  row("max_feed_mm_min", "max speed", summary.max_feed_mm_min,
      fmt::format("{:.1f} mm/min (limit {:.0f}, rapid {:.0f})", summary.max_feed_mm_min,
                  machine.max_feed_mm_min, machine.rapid_mm_min));
  row("max_tangential_accel_mm_s2", "max tangential acceleration",
      summary.max_tangential_accel_mm_s2,
      fmt::format("{:.1f} mm/s² (limit {:.0f})", summary.max_tangential_accel_mm_s2,
                  machine.max_accel_mm_s2));
  row("max_path_accel_mm_s2", "max resultant acceleration", summary.max_path_accel_mm_s2,
      fmt::format("{:.1f} mm/s²", summary.max_path_accel_mm_s2));
  row("max_contour_error_mm", "max contour error", summary.max_contour_error_mm,
      fmt::format("{:.4f} mm (tolerance {:g})", summary.max_contour_error_mm,
                  machine.contour_tolerance_mm));
  o += fmt::format("<tr><th>mode</th><td id=\"s-mode\">{}</td></tr>\n", html_escape(summary.mode));
  for (const std::string& w : summary.warnings) {
    o += "<tr><th>warning</th><td class=\"warn\">" + html_escape(w) + "</td></tr>\n";
  }
  o += "</table>\n";

  o += "<h2>Speed</h2>\n<div id=\"speed-chart\"></div>\n";
  o += "<h2>Acceleration</h2>\n<div id=\"accel-chart\"></div>\n";
  o += "<section id=\"extra-section\" hidden><h2>Correction and load</h2>"
       "<div id=\"extra-chart\"></div></section>\n";
  o += fmt::format(
      "<div class=\"note\">{} samples shown as {} buckets of {}+ cycles each (minimum and "
      "maximum of every bucket drawn).</div>\n",
      report.samples(), bk.size(), bk.empty() ? 0 : bk.front().samples);
  o += "<h2>Top view (X/Y), coloured by speed</h2>\n<canvas id=\"path-canvas\"></canvas>\n";
  o += "<div class=\"note\">Blue slow, red fast; rapid moves dashed grey; circles: the slowest "
       "lines below.</div>\n";

  o += fmt::format("<h2>The {} slowest lines</h2>\n", slow.size());
  o += "<table class=\"slow\" id=\"slowest\"><tr><th>#</th><th class=\"num\">line</th>"
       "<th>program</th><th class=\"num\">time lost (s)</th><th class=\"num\">min speed "
       "(mm/min)</th><th class=\"num\">asked (mm/min)</th><th class=\"num\">visits</th>";
  if (report.has_override()) o += "<th class=\"num\">override (%)</th>";
  if (report.has_correction()) o += "<th class=\"num\">correction</th>";
  if (report.has_load()) o += "<th class=\"num\">load (%)</th>";
  o += "<th>why</th></tr>\n";
  for (std::size_t i = 0; i < slow.size(); ++i) {
    const ReportSlowSpot& s = slow[i];
    const auto text = texts.find(s.line);
    // A merged line (collinear pieces run as one): its first piece's text, and the range.
    const bool merged = s.last_line != 0 && s.last_line != s.line;
    o += fmt::format(
        "<tr><td>{}</td><td class=\"num\">{}</td><td><code>{}</code>{}</td><td "
        "class=\"num\">{:.3f}</td><td class=\"num\">{:.0f}</td><td class=\"num\">{:.0f}</td>"
        "<td class=\"num\">{}</td>",
        i + 1, merged ? fmt::format("{}–{}", s.line, s.last_line) : fmt::format("{}", s.line),
        text == texts.end() ? "" : html_escape(text->second),
        merged ? fmt::format(" … (collinear lines run as one, through line {})", s.last_line)
               : std::string(),
        s.lost_s, s.min_speed_mm_min, s.target_mm_min, s.visits);
    if (report.has_override()) o += fmt::format("<td class=\"num\">{:.0f}</td>", s.override_pct);
    if (report.has_correction()) {
      o += std::isnan(s.correction) ? std::string("<td></td>")
                                    : fmt::format("<td class=\"num\">{:.3f}</td>", s.correction);
    }
    if (report.has_load()) {
      o += std::isnan(s.load_pct) ? std::string("<td></td>")
                                  : fmt::format("<td class=\"num\">{:.1f}</td>", s.load_pct);
    }
    o += "<td>" + html_escape(s.why) + "</td></tr>\n";
  }
  o += "</table>\n";
  o += "<div class=\"note\">Time lost: time on the line minus the time at the asked speed "
       "(programmed feed × override, capped by the machine). Charts: uPlot (MIT).</div>\n";

  o += page::tail(data, kPageScript);
  return o;
}

}  // namespace cncore::io
