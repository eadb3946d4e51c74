// plan_tables: validation against the machine, effective tables (values at t = 0) and the
// per-axis limit check; format_effective: the listing behind --print-effective.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "core/error.hpp"
#include "tables/analysis.hpp"

namespace cncore::tables {

std::string Diagnostic::formatted() const {
  return fmt::format("{}:{}:{}: {}: {}", file, line, col,
                     severity == Severity::kError ? "error" : "warning", message);
}

std::size_t post_filter_cycles(const MachineConfig& machine) {
  if (!(machine.period_s > 0)) return 1;
  return std::max<std::size_t>(
      1, static_cast<std::size_t>(std::llround(machine.post_filter_s / machine.period_s)));
}

bool TablePlan::has_errors() const {
  return std::any_of(diagnostics.begin(), diagnostics.end(), [](const Diagnostic& d) {
    return d.severity == Diagnostic::Severity::kError;
  });
}

namespace {

const char* unit_of(const MachineConfig& m, std::size_t axis) {
  return m.axes[axis].rotary ? "deg" : "mm";
}

// Analyses `repetitions` repetitions of a table with the values at t = 0.
std::vector<EffectivePoint> analyse(const Table& t, const RunOptions& o, double start_ref,
                                    const AxisVec& start_pos, std::uint32_t repetitions) {
  detail::Analyzer an(t, o.settings.cancel_mode, start_ref, start_pos, repetitions);
  std::vector<EffectivePoint> pts;
  EffectivePoint p;
  while (an.next(o.values, 0.0, p)) pts.push_back(p);
  return pts;
}

struct LimitCheck {
  const MachineConfig& m;
  double rate;  // reference units per second
  std::vector<Diagnostic>& out;
  double max_ratio = 1;  // largest (needed / allowed) rate factor among errors
  std::set<std::tuple<std::size_t, std::int32_t, std::size_t, int>> seen;

  // Blames the row of point i, or of the first real row for the implicit start point.
  // Returns false when this row was already reported for this axis and kind (a cyclic table's
  // rows appear twice in the checked points). With `quiet` it only records the row.
  bool report(const Table& t, const std::vector<EffectivePoint>& pts, std::size_t i, std::size_t ti,
              std::size_t axis, int kind, Diagnostic::Severity sev, const std::string& msg,
              bool quiet = false) {
    std::size_t j = i;
    while (j < pts.size() && pts[j].row < 0) ++j;
    if (j == pts.size()) return false;
    const Row& row = t.rows[static_cast<std::size_t>(pts[j].row)];
    if (!seen.insert({ti, pts[j].row, axis, kind}).second) return false;
    if (!quiet) out.push_back({sev, t.file, row.line, row.col, msg});
    return true;
  }

  std::string seg_text(const Table& t, const std::vector<EffectivePoint>& pts, std::size_t i) {
    auto line_of = [&](std::size_t k) -> std::string {
      if (pts[k].row < 0) return "the start";
      return fmt::format("line {}", t.rows[static_cast<std::size_t>(pts[k].row)].line);
    };
    return fmt::format("between {} and {} (reference {:.6g} to {:.6g})", line_of(i), line_of(i + 1),
                       pts[i].ref, pts[i + 1].ref);
  }

  // The seed's linear distribution changes the velocity in one step at a control point. The
  // post-interpolation moving average over N = post_filter_cycles cycles (run_tables applies it)
  // turns the step into a ramp over N·τ: a = |Δv| / (N·τ). Slowing the reference by k divides
  // Δv, so a by k (not k²). Listed for the first few rows of each axis, then counted.
  template <typename Slope>
  void check_velocity_steps(const Table& t, std::size_t ti, const std::vector<EffectivePoint>& pts,
                            std::size_t axis, const Slope& slope) {
    constexpr int kListed = 5;
    const AxisConfig& ac = m.axes[axis];
    const char letter = kAxisLetters[axis];
    const char* unit = unit_of(m, axis);
    const std::size_t n = pts.size();
    const double step_s = static_cast<double>(post_filter_cycles(m)) * m.period_s;
    int listed = 0, more = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double v_in = i == 0 ? 0 : slope(i - 1);
      const double v_out = i + 1 == n ? 0 : slope(i);
      const double dv_s = std::abs(v_out - v_in) * rate;
      const double a = dv_s / step_s;
      if (a <= ac.max_accel_mm_s2 * (1 + 1e-9)) continue;
      max_ratio = std::max(max_ratio, a / ac.max_accel_mm_s2);
      const bool quiet = listed >= kListed;
      const bool fresh = report(
          t, pts, i, ti, axis, 3, Diagnostic::Severity::kError,
          fmt::format("{} velocity steps by {:.6g} {}/s at this control point (LINEAR): {:.6g} "
                      "{}/s² over {:.6g} ms exceeds the axis limit {:.6g} {}/s² (fits with CUBIC, "
                      "[motion] post_filter_s >= {:.3g} s, or slow_to_fit)",
                      letter, dv_s, unit, a, unit, step_s * 1000, ac.max_accel_mm_s2, unit,
                      std::ceil(dv_s / ac.max_accel_mm_s2 / m.period_s) * m.period_s),
          quiet);
      if (fresh) (quiet ? more : listed) += 1;
    }
    if (more > 0) {
      out.push_back({Diagnostic::Severity::kError, t.file, t.ref_line, t.ref_col,
                     fmt::format("{} velocity steps beyond the axis acceleration limit at {} "
                                 "more control points of this table (not listed)",
                                 letter, more)});
    }
  }

  void check(const Table& t, std::size_t ti, const std::vector<EffectivePoint>& pts) {
    const std::size_t n = pts.size();
    for (std::size_t axis = 0; axis < kMaxAxes; ++axis) {
      if (!((t.axis_mask >> axis) & 1U)) continue;
      const AxisConfig& ac = m.axes[axis];
      const char letter = kAxisLetters[axis];
      const char* unit = unit_of(m, axis);
      // Travel: the curve stays between its control points (linear, and monotone cubic).
      for (std::size_t i = 0; i < n; ++i) {
        double p = pts[i].position[axis];
        if (p < ac.min_mm - 1e-9 || p > ac.max_mm + 1e-9) {
          report(t, pts, i, ti, axis, 0, Diagnostic::Severity::kError,
                 fmt::format("{} {:.6g} {} is outside the axis travel {:.6g} … {:.6g}", letter, p,
                             unit, ac.min_mm, ac.max_mm));
        }
      }
      if (rate <= 0 || n < 2) continue;
      std::vector<double> tangent(n, 0.0);
      if (t.interp == Interp::kCubic) {
        for (std::size_t i = 1; i + 1 < n; ++i) {
          tangent[i] = detail::pchip_tangent(pts[i - 1].ref, pts[i - 1].position[axis], pts[i].ref,
                                             pts[i].position[axis], pts[i + 1].ref,
                                             pts[i + 1].position[axis]);
        }
      }
      auto slope = [&](std::size_t i) {
        return (pts[i + 1].position[axis] - pts[i].position[axis]) / (pts[i + 1].ref - pts[i].ref);
      };
      for (std::size_t i = 0; i + 1 < n; ++i) {
        double v_mm_min = 0, a_mm_s2 = 0;
        if (t.interp == Interp::kLinear) {
          v_mm_min = std::abs(slope(i)) * rate * 60.0;  // Δp/Δref · ref/s · 60 s/min
        } else {
          auto e =
              detail::hermite_extremes(pts[i].position[axis], pts[i + 1].position[axis], tangent[i],
                                       tangent[i + 1], pts[i + 1].ref - pts[i].ref);
          v_mm_min = e.slope * rate * 60.0;
          a_mm_s2 = e.curvature * rate * rate;  // d²p/dref² · (dref/dt)²
        }
        if (v_mm_min > ac.max_speed_mm_min * (1 + 1e-9)) {
          max_ratio = std::max(max_ratio, v_mm_min / ac.max_speed_mm_min);
          report(
              t, pts, i + 1, ti, axis, 1, Diagnostic::Severity::kError,
              fmt::format("{} speed {:.6g} {}/min {} exceeds the axis limit {:.6g} {}/min", letter,
                          v_mm_min, unit, seg_text(t, pts, i), ac.max_speed_mm_min, unit));
        }
        if (a_mm_s2 > ac.max_accel_mm_s2 * (1 + 1e-9)) {
          max_ratio = std::max(max_ratio, std::sqrt(a_mm_s2 / ac.max_accel_mm_s2));
          report(t, pts, i + 1, ti, axis, 2, Diagnostic::Severity::kError,
                 fmt::format("{} acceleration {:.6g} {}/s² {} exceeds the axis limit {:.6g} {}/s²",
                             letter, a_mm_s2, unit, seg_text(t, pts, i), ac.max_accel_mm_s2, unit));
        }
      }
      if (t.interp == Interp::kLinear) check_velocity_steps(t, ti, pts, axis, slope);
    }
  }
};

}  // namespace

// Size: validation, effective tables, limits and the slow-to-fit factor in the order the
// plan is built; each step reads what the previous one produced.
TablePlan plan_tables(std::vector<Table> tables, const MachineConfig& machine,
                      const RunOptions& options) {
  TablePlan plan;
  plan.machine = machine;
  plan.options = options;
  if (tables.empty()) throw InputError("", 0, 0, "no table to run");
  if (!(machine.period_s > 0)) throw InputError("", 0, 0, "interpolation period must be > 0");

  // Validation: configured axes, one table per axis, one reference for all tables.
  std::uint32_t driven = 0;
  const Table& first = tables.front();
  for (const Table& t : tables) {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (!((t.axis_mask >> a) & 1U)) continue;
      if (!machine.axes[a].enabled) {
        throw InputError(t.file, t.axes_line, t.axis_cols[a],
                         fmt::format("axis {} is not configured on this machine", kAxisLetters[a]));
      }
      if ((driven >> a) & 1U) {
        throw InputError(
            t.file, t.axes_line, t.axis_cols[a],
            fmt::format("axis {} is already driven by another table", kAxisLetters[a]));
      }
      driven |= 1U << a;
    }
    if (t.ref_kind != first.ref_kind ||
        (t.ref_kind == RefKind::kAxis && t.ref_axis != first.ref_axis)) {
      throw InputError(t.file, t.ref_line, t.ref_col,
                       fmt::format("reference differs from the first table's ({}:{})", first.file,
                                   first.ref_line));
    }
  }
  if (first.ref_kind == RefKind::kAxis) {
    std::size_t ra = first.ref_axis;
    if (!machine.axes[ra].enabled) {
      throw InputError(
          first.file, first.ref_line, first.ref_col,
          fmt::format("reference axis {} is not configured on this machine", kAxisLetters[ra]));
    }
    if ((driven >> ra) & 1U) {
      throw InputError(first.file, first.ref_line, first.ref_col,
                       fmt::format("reference axis {} is driven by a table", kAxisLetters[ra]));
    }
  }
  const ReferenceSource& src = options.reference;
  if (!src.position && !(src.rate_per_s > 0)) {
    throw InputError(first.file, first.ref_line, first.ref_col,
                     "the reference does not advance (rate must be > 0)");
  }

  for (std::size_t i = 0; i < kMaxAxes; ++i) plan.start_position[i] = machine.start_position[i];
  double start_ref = src.position ? src.position(0.0) : src.start;
  plan.start_ref = start_ref;
  if (first.ref_kind == RefKind::kAxis) plan.start_position[first.ref_axis] = start_ref;

  // Effective tables (throws on references going backwards, undefined amounts) and the points
  // the limit check walks: two repetitions of a cyclic table cover its lead-in and wrap.
  std::vector<std::vector<EffectivePoint>> check_points;
  for (const Table& t : tables) {
    plan.effective.push_back(analyse(t, options, start_ref, plan.start_position, 1));
    const auto& pts = plan.effective.back();
    // A first row at the start reference defines where its axes start.
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if ((t.axis_mask >> a) & 1U) plan.start_position[a] = pts.front().position[a];
    }
    if (t.cyclic) {
      const EffectivePoint& last = pts.back();
      auto first_row = std::find_if(pts.begin(), pts.end(), [](auto& p) { return p.row == 0; });
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (((t.axis_mask >> a) & 1U) &&
            std::abs(first_row->position[a] - last.position[a]) > 1e-9) {
          const Row& r = t.rows.back();
          throw InputError(t.file, r.line, r.col,
                           fmt::format("a CYCLIC table must end where it starts: {} is {:.6g} here "
                                       "and {:.6g} at the first row",
                                       kAxisLetters[a], last.position[a], first_row->position[a]));
        }
      }
    }
    std::uint32_t reps =
        t.cyclic ? (t.cyclic_repeats ? t.cyclic_repeats : options.cyclic_repeats) : 1;
    check_points.push_back(analyse(t, options, start_ref, plan.start_position, std::min(reps, 2U)));
  }

  // Limits. The rate converts per-reference slopes into per-second speeds.
  double rate = src.rate_per_s;
  auto run_check = [&](double r, std::vector<Diagnostic>& out) {
    LimitCheck lc{machine, r, out, 1.0, {}};
    for (std::size_t ti = 0; ti < tables.size(); ++ti) lc.check(tables[ti], ti, check_points[ti]);
    if (first.ref_kind == RefKind::kAxis && !src.position) {
      const AxisConfig& ac = machine.axes[first.ref_axis];
      double v = r * 60.0;
      if (v > ac.max_speed_mm_min * (1 + 1e-9)) {
        lc.max_ratio = std::max(lc.max_ratio, v / ac.max_speed_mm_min);
        out.push_back({Diagnostic::Severity::kError, first.file, first.ref_line, first.ref_col,
                       fmt::format("master axis {} speed {:.6g}/min exceeds its limit {:.6g}/min",
                                   kAxisLetters[first.ref_axis], v, ac.max_speed_mm_min)});
      }
    }
    return lc.max_ratio;
  };
  if (src.position && rate <= 0) {
    plan.diagnostics.push_back(
        {Diagnostic::Severity::kWarning, first.file, first.ref_line, first.ref_col,
         "axis speed and acceleration limits not checked beforehand: the master axis has no "
         "nominal rate (moved by a part program); the summary reports the measured ones"});
    rate = 0;
  }
  std::vector<Diagnostic> diags;
  double ratio = run_check(rate, diags);
  bool limit_errors = std::any_of(diags.begin(), diags.end(), [](const Diagnostic& d) {
    return d.severity == Diagnostic::Severity::kError &&
           d.message.find("travel") == std::string::npos;
  });
  if (limit_errors && options.settings.slow_to_fit && !src.position) {
    // One constant factor for the whole reference: speeds scale with 1/k, accelerations with
    // 1/k², so k = max(v/vmax, sqrt(a/amax)) over all violations makes every segment fit.
    plan.slow_factor = ratio * (1 + 1e-9);
    for (Diagnostic& d : diags) {
      if (d.severity == Diagnostic::Severity::kError &&
          d.message.find("travel") == std::string::npos) {
        d.severity = Diagnostic::Severity::kWarning;
        d.message += fmt::format("; reference slowed by the factor {:.4g}", plan.slow_factor);
      }
    }
    plan.diagnostics.insert(plan.diagnostics.end(), diags.begin(), diags.end());
    plan.diagnostics.push_back(
        {Diagnostic::Severity::kWarning, first.file, first.ref_line, first.ref_col,
         fmt::format("reference rate slowed to 1/{:.4g} so that every table fits the axis limits "
                     "(slow_to_fit): the cycle takes {:.4g} times as long",
                     plan.slow_factor, plan.slow_factor)});
  } else {
    plan.diagnostics.insert(plan.diagnostics.end(), diags.begin(), diags.end());
  }
  plan.tables = std::move(tables);
  return plan;
}

ReferenceSource default_reference(const Table& first, const MachineConfig& machine,
                                  double spindle_rpm, double master_speed_mm_min) {
  switch (first.ref_kind) {
    case RefKind::kTime:
      return ReferenceSource::time_clock();
    case RefKind::kSpindle:
      if (!(spindle_rpm > 0)) {
        throw InputError(first.file, first.ref_line, first.ref_col,
                         "REF SPINDLE needs a spindle speed > 0 rpm");
      }
      return ReferenceSource::spindle(spindle_rpm);
    case RefKind::kAxis:
      if (!(master_speed_mm_min > 0)) {
        throw InputError(
            first.file, first.ref_line, first.ref_col,
            fmt::format("REF AXIS {} needs a master axis speed > 0", kAxisLetters[first.ref_axis]));
      }
      return ReferenceSource::master_axis(machine.start_position[first.ref_axis],
                                          master_speed_mm_min);
  }
  return ReferenceSource::time_clock();
}

std::string format_effective(const TablePlan& plan) {
  std::string s;
  const char* mode = plan.options.settings.cancel_mode == CancelMode::kClear ? "clear" : "rebase";
  for (std::size_t ti = 0; ti < plan.tables.size(); ++ti) {
    const Table& t = plan.tables[ti];
    s += fmt::format("; effective table of {} (shifts applied, SFTCAN mode {}, values at t = 0)\n",
                     t.file, mode);
    switch (t.ref_kind) {
      case RefKind::kTime:
        s += "REF TIME\n";
        break;
      case RefKind::kAxis:
        s += fmt::format("REF AXIS {}\n", kAxisLetters[t.ref_axis]);
        break;
      case RefKind::kSpindle:
        s += "REF SPINDLE\n";
        break;
    }
    s += "AXES";
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if ((t.axis_mask >> a) & 1U) s += fmt::format(" {}", kAxisLetters[a]);
    }
    s += t.interp == Interp::kLinear ? "\nLINEAR\n" : "\nCUBIC\n";
    if (t.cyclic) {
      std::uint32_t reps = t.cyclic_repeats ? t.cyclic_repeats : plan.options.cyclic_repeats;
      s += fmt::format("CYCLIC {}\n", reps);
    }
    for (const EffectivePoint& p : plan.effective[ti]) {
      std::string row = fmt::format("L{}", p.ref);
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if ((t.axis_mask >> a) & 1U) row += fmt::format(" {}{}", kAxisLetters[a], p.position[a]);
      }
      if (p.row < 0) {
        s += fmt::format("; start: {} (implicit start point)\n", row);
        continue;
      }
      const Row& r = t.rows[static_cast<std::size_t>(p.row)];
      for (int m : r.m_codes) row += fmt::format(" M{}", m);
      s += fmt::format("{:<40} ; line {}: written L{}", row, r.line, r.ref_written);
      if (r.cancel) s += ", SFTCAN";
      if (r.shift.kind != Shift::Kind::kNone) s += ", SFT";
      if (p.shift != 0) s += fmt::format(", shift {}", p.shift);
      s += p.shifting ? ", shifting on\n" : "\n";
    }
    if (plan.slow_factor > 1) {
      s += fmt::format("; reference rate slowed by the factor {:.6g}\n", plan.slow_factor);
    }
    s += "\n";
  }
  return s;
}

}  // namespace cncore::tables
