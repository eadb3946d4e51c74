// The HTML report's slow spots and what the time lost went to, from the summary's own shares
// of each cycle (TimeShare, SummaryObserver::share): the report ranks the same time lost as the
// summary, line by line, and every block passed within a cycle has its part.
#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "io/report.hpp"

namespace cncore::io {

namespace {

constexpr std::size_t kSlowCandidates = 64;

std::size_t index(LossCause c) {
  return static_cast<std::size_t>(c);
}

}  // namespace

const char* loss_cause_name(LossCause cause) {
  switch (cause) {
    case LossCause::kCorners:
      return "corners";
    case LossCause::kArcs:
      return "arcs";
    case LossCause::kShortSegments:
      return "short segments";
    case LossCause::kStops:
      return "stops";
    case LossCause::kAcceleration:
      return "acceleration";
    case LossCause::kFeedLimit:
      return "feed limit";
    case LossCause::kOverride:
      return "override";
  }
  return "";
}

std::string loss_cause_key(LossCause cause) {
  std::string key = loss_cause_name(cause);
  std::replace(key.begin(), key.end(), ' ', '_');
  return key;
}

void ReportObserver::on_share(const TimeShare& sh) {
  const motion::Sample& s = *sh.sample;
  if (!group_.active || sh.line != group_.spot.line || sh.rapid != group_.spot.rapid) {
    // Close the previous line first: its block is still at the front of explain_pending_.
    close_group();
    group_.active = true;
    group_.spot = ReportSlowSpot{};
    group_.spot.line = sh.line;
    group_.spot.rapid = sh.rapid;
    group_.spot.min_speed_mm_min = INFINITY;
    group_.t_start_s = s.t_s - sh.dt_s;
    group_.first_speed_mm_min = -1;
    group_.last_speed_mm_min = 0;
  }
  Pending* b = current_block(explain_pending_, sh.line);
  if (b != nullptr && !b->scanned) {
    // As far as a limit can slow the tool from the asked speed: T²/(2A).
    const double t = sh.target_mm_min / 60;
    scan_ahead(*b, t * t / (2 * machine_.max_accel_mm_s2));
  }
  ReportSlowSpot& g = group_.spot;
  g.last_line = sh.last_line;
  if (!(sh.dt_s > 0)) return;
  const double v_mm_min = sh.length_mm / sh.dt_s * 60;
  g.time_s += sh.dt_s;
  g.length_mm += sh.length_mm;
  g.lost_s += sh.lost_s;
  (sh.rapid ? losses_.rapid_s : losses_.cutting_s) += sh.lost_s;
  group_.t_end_s = s.t_s;
  if (group_.first_speed_mm_min < 0) group_.first_speed_mm_min = v_mm_min;
  group_.last_speed_mm_min = v_mm_min;
  // The slowest share of the visit, measured against what was asked there.
  const double target = sh.target_mm_min;
  const double ratio = target > 0 ? v_mm_min / target : 1;
  const double best = g.target_mm_min > 0 ? g.min_speed_mm_min / g.target_mm_min : INFINITY;
  if (ratio < best) {
    g.min_speed_mm_min = v_mm_min;
    g.target_mm_min = target;
    g.t_min_s = s.t_s;
    g.x_mm = s.position[0];
    g.y_mm = s.position[1];
    g.override_pct = s.override_pct;
    g.correction = s.correction;
    g.load_pct = s.load_pct;
    g.load_target_pct = s.load_target_pct;
  }
  attribute(sh, b);
}

// What a share's time lost against F as written went to. With F the programmed feed, O the
// override, C the machine's limit of the move and T = min(F·O, C) (speeds in mm/min, the share
// moved length ℓ in dt):
//  override    ℓ/(F·O) − ℓ/F     (negative when the override raises the feed)
//  feed limit  ℓ/T − ℓ/(F·O)     (C below F·O)
//  the rest    the summary's lost_s = max(0, dt − ℓ/T), split by dynamics:
//   arcs       on an arc whose normal acceleration caps the speed at √(A·R) < T:
//              ℓ/√(A·R) − ℓ/T of it (at most lost_s);
//   what is left goes whole to one cause, dynamic_cause().
// A share at override 0 (a feed hold) is all override. So the causes add up to the time lost
// against F as written: Σ dt − ℓ/F over the cycles (to the shares that ran faster than T).
void ReportObserver::attribute(const TimeShare& sh, const Pending* b) {
  auto& c = losses_.cause_s;
  const double len = sh.length_mm;
  const double f = sh.programmed_mm_min, t = sh.target_mm_min;
  if (!(t > 0)) {
    c[index(LossCause::kOverride)] += sh.dt_s;
    return;
  }
  const double fo = f * sh.sample->override_pct / 100;
  if (f > 0 && fo > 0) {
    c[index(LossCause::kOverride)] += len * 60 / fo - len * 60 / f;
    c[index(LossCause::kFeedLimit)] += len * 60 / t - len * 60 / fo;
  }
  const double lost = sh.lost_s;
  if (!(lost > 0)) return;
  double arc = 0;
  if (b != nullptr && b->arc_limit_mm_min > 0 && b->arc_limit_mm_min < 0.99 * t) {
    arc = std::clamp(len * 60 / b->arc_limit_mm_min - len * 60 / t, 0.0, lost);
  }
  c[index(LossCause::kArcs)] += arc;
  if (lost - arc > 0) {
    c[index(b != nullptr ? dynamic_cause(sh, *b) : LossCause::kAcceleration)] += lost - arc;
  }
}

// The one dynamic cause of a share's loss. The tool is at d₀ from its block's start and d₁ from
// its end; the nearest stop, corner (a direction change ≥ kCornerDeg) and arc behind the start
// and ahead of the end are known (Pending::from_*, to_*). Each bounds the speed at the tool by
// its braking ramp, v² ≤ v꜀² + 2·A·d (A the machine's acceleration, d the distance to it, v꜀
// the speed it allows: 0 at a stop or a corner, √(A·R) on an arc of radius R). The loss goes to
//  arcs            the block itself is an arc with √(A·R) below the asked speed T; else
//  the lowest bound below T (the limit that holds the tool back): stops (program start and
//                  end, dwells, waiting M codes, exact stop, stop mode), corners or arcs; else
//  short segments  the block is shorter than one cycle's travel at T (T·τ): a chain of
//                  sub-cycle blocks turning less than a corner each, which the planner slows
//                  for as a curve; else
//  acceleration    the ramp to a new feed, or to a limit beyond the look-ahead.
LossCause ReportObserver::dynamic_cause(const TimeShare& sh, const Pending& b) const {
  const double a = machine_.max_accel_mm_s2;
  const double t = sh.target_mm_min / 60;  // mm/s
  const double len = b.length_mm;
  if (b.arc_limit_mm_min > 0 && b.arc_limit_mm_min < 0.99 * sh.target_mm_min) {
    return LossCause::kArcs;
  }
  // Where the tool is: a block passed whole within the cycle counts from its middle; else the
  // nearest point of the programmed move to the cycle's on-path point.
  double along = len / 2;
  if (sh.length_mm < 0.9 * len) along = b.move.nearest(sh.sample->path_position.xyz()).along_mm;
  const double d0 = along, d1 = std::max(0.0, len - along);
  double best_v2 = 0.98 * t * t;  // a bound counts below (0.99·T)²
  auto cause = LossCause::kAcceleration;
  bool found = false;
  auto consider = [&](LossCause c, double vc_mm_s, double d_mm) {
    const double v2 = vc_mm_s * vc_mm_s + 2 * a * d_mm;
    if (v2 < best_v2) {
      best_v2 = v2;
      cause = c;
      found = true;
    }
  };
  consider(LossCause::kStops, 0, d0 + b.from_stop_mm);
  consider(LossCause::kStops, 0, d1 + b.to_stop_mm);
  consider(LossCause::kCorners, 0, d0 + b.from_corner_mm);
  consider(LossCause::kCorners, 0, d1 + b.to_corner_mm);
  if (b.from_arc_limit_mm_min > 0) {
    consider(LossCause::kArcs, b.from_arc_limit_mm_min / 60, d0 + b.from_arc_mm);
  }
  if (b.to_arc_limit_mm_min > 0) {
    consider(LossCause::kArcs, b.to_arc_limit_mm_min / 60, d1 + b.to_arc_mm);
  }
  if (found) return cause;
  if (len < t * machine_.period_s) return LossCause::kShortSegments;
  return LossCause::kAcceleration;
}

// The nearest stop, corner and arc ahead of b's end (b at the front of explain_pending_), as
// far as within_mm: the blocks handed to the kernel after it. A block the kernel has no
// successor for yet ends at a stop (the kernel plans it so).
void ReportObserver::scan_ahead(Pending& b, double within_mm) {
  b.scanned = true;
  if (b.stop_after || !b.has_successor) {
    b.to_stop_mm = 0;
    return;
  }
  double d = 0;  // from b's end to the start of block k
  for (std::size_t k = 1; k < explain_pending_.size() && d <= within_mm; ++k) {
    const Pending& n = explain_pending_[k];
    if (n.stop_before) {
      b.to_stop_mm = d;
      return;
    }
    if (n.entry_corner_deg >= kCornerDeg && std::isinf(b.to_corner_mm)) b.to_corner_mm = d;
    if (n.arc_limit_mm_min > 0 && std::isinf(b.to_arc_mm)) {
      b.to_arc_mm = d;
      b.to_arc_limit_mm_min = n.arc_limit_mm_min;
    }
    d += n.length_mm;
    if (n.stop_after || !n.has_successor) {
      b.to_stop_mm = d;
      return;
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
  const Pending* b = !explain_pending_.empty() && explain_pending_.front().line == g.line
                         ? &explain_pending_.front()
                         : nullptr;
  const double span = group_.t_end_s - group_.t_start_s;
  const double fraction = span > 0 ? (g.t_min_s - group_.t_start_s) / span : 0;
  // At standstill: below 2 % of the asked speed, or within one cycle's speed change of 0 — a
  // sampled stop lands with a last step of up to Amax·τ (the acceleration type does).
  const double one_cycle_mm_min = machine_.max_accel_mm_s2 * machine_.period_s * 60.0 * 1.001;
  const double still = std::max(0.02 * std::max(g.target_mm_min, 1.0), one_cycle_mm_min);
  const bool start_stopped = group_.first_speed_mm_min < still;
  const bool end_stopped = group_.last_speed_mm_min < still;
  g.visits = 1;
  std::vector<ReportSlowSpot>& top = g.rapid ? top_rapid_ : top_;
  auto same = std::find_if(top.begin(), top.end(),
                           [&](const ReportSlowSpot& s) { return s.line == g.line; });
  if (same != top.end()) {
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
  if (top.size() < kSlowCandidates) {
    top.push_back(g);
    return;
  }
  auto least = std::min_element(top.begin(), top.end(),
                                [](const auto& x, const auto& y) { return x.lost_s < y.lost_s; });
  if (g.lost_s > least->lost_s) *least = g;
}

namespace {

std::vector<ReportSlowSpot> ranked(std::vector<ReportSlowSpot> v, std::size_t n) {
  std::sort(v.begin(), v.end(), [](const auto& x, const auto& y) {
    return x.lost_s != y.lost_s ? x.lost_s > y.lost_s : x.line < y.line;
  });
  if (v.size() > n) v.resize(n);
  return v;
}

}  // namespace

std::vector<ReportSlowSpot> ReportObserver::slowest() const {
  return ranked(top_, options_.slow_spots);
}

std::vector<ReportSlowSpot> ReportObserver::slowest_rapids() const {
  return ranked(top_rapid_, options_.slow_spots);
}

std::string summary_json_with_losses(const std::string& summary_json, const ReportLosses& losses) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(summary_json);
  nlohmann::ordered_json c = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < kLossCauses; ++i) {
    c[loss_cause_key(static_cast<LossCause>(i))] = losses.cause_s[i];
  }
  c["total"] = losses.total_s();
  j["time_lost_by_cause_s"] = c;
  return j.dump(2) + "\n";
}

}  // namespace cncore::io
