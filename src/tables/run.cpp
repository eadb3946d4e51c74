// The distribution (the seed's section 12): once per interpolation period, the reference value
// from the source → each table's segment → axis positions. Rows are read lazily (LINEAR: when
// the segment that ends at the row starts; CUBIC: one row earlier, because the tangent at a
// segment's end needs the next point), so signals changed during the run apply to the rows
// read after the change. Per cycle the work is bounded and nothing is allocated once the
// sample's M-code list has reached its largest size.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "tables/analysis.hpp"

namespace cncore::tables {
namespace {

class Cursor {
 public:
  Cursor(const Table& t, const TablePlan& plan, double start_ref)
      : t_(&t),
        values_(&plan.options.values),
        cubic_(t.interp == Interp::kCubic),
        an_(t, plan.options.settings.cancel_mode, start_ref, plan.start_position,
            t.cyclic ? (t.cyclic_repeats ? t.cyclic_repeats : plan.options.cyclic_repeats) : 1) {}

  // Reads the first points at t = 0; the start point's M codes fire in the first cycle.
  void start(std::uint8_t index, std::vector<MEvent>& events) {
    index_ = index;
    an_.next(*values_, 0.0, p0_);  // plan_tables has already read this table once
    fire(p0_, events);
    has_p1_ = an_.next(*values_, 0.0, p1_);
    if (cubic_ && has_p1_) has_p2_ = an_.next(*values_, 0.0, p2_);
    m0_ = AxisVec{};  // the table starts at rest
    m1_ = tangents_at_p1();
    done_ = !has_p1_;
  }

  // Passes every control point the reference has reached (reading further rows at t_s).
  void advance(double ref, double t_s, std::vector<MEvent>& events) {
    while (!done_ && ref >= p1_.ref - 1e-9 * std::max(1.0, std::abs(p1_.ref))) {
      fire(p1_, events);
      p0_ = p1_;
      m0_ = m1_;
      if (cubic_) {
        has_p1_ = has_p2_;
        if (has_p1_) {
          p1_ = p2_;
          has_p2_ = an_.next(*values_, t_s, p2_);
        }
      } else {
        has_p1_ = an_.next(*values_, t_s, p1_);
      }
      if (has_p1_) m1_ = tangents_at_p1();
      done_ = !has_p1_;
      if (!done_) check_segment(t_s);
    }
  }

  // Rows read during the run may differ from the plan (signals changed): a segment that now
  // exceeds an axis speed (or, CUBIC, acceleration) limit is reported as a run warning.
  void watch_limits(const MachineConfig& m, double rate_per_s, std::vector<std::string>* out) {
    machine_ = &m;
    rate_ = rate_per_s;
    warnings_ = out;
  }

  // Positions of this table's axes at `ref`.
  void evaluate(double ref, AxisVec& pos) const {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (!((t_->axis_mask >> a) & 1U)) continue;
      if (done_) {
        pos[a] = p0_.position[a];
        continue;
      }
      double h = p1_.ref - p0_.ref;
      double u = std::clamp((ref - p0_.ref) / h, 0.0, 1.0);
      if (cubic_) {
        pos[a] = detail::hermite(p0_.position[a], p1_.position[a], m0_[a], m1_[a], h, u);
      } else {
        // The seed: movement per reference unit = Δcoordinate / Δreference.
        pos[a] = p0_.position[a] + (p1_.position[a] - p0_.position[a]) * u;
      }
    }
  }

  bool done() const { return done_; }
  std::uint32_t active_line() const {
    const EffectivePoint& p = done_ ? p0_ : p1_;
    return p.row < 0 ? 0 : t_->rows[static_cast<std::size_t>(p.row)].line;
  }
  double end_ref() const { return done_ ? p0_.ref : p1_.ref; }

 private:
  AxisVec tangents_at_p1() const {
    AxisVec m;
    if (!cubic_ || !has_p2_) return m;  // LINEAR, or the last point: the table ends at rest
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if ((t_->axis_mask >> a) & 1U) {
        m[a] = detail::pchip_tangent(p0_.ref, p0_.position[a], p1_.ref, p1_.position[a], p2_.ref,
                                     p2_.position[a]);
      }
    }
    return m;
  }
  void check_segment(double t_s) {
    if (machine_ == nullptr || rate_ <= 0) return;
    const double h = p1_.ref - p0_.ref;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (!((t_->axis_mask >> a) & 1U)) continue;
      const AxisConfig& ac = machine_->axes[a];
      double v_mm_min = 0, a_mm_s2 = 0;
      if (cubic_) {
        auto e = detail::hermite_extremes(p0_.position[a], p1_.position[a], m0_[a], m1_[a], h);
        v_mm_min = e.slope * rate_ * 60.0;
        a_mm_s2 = e.curvature * rate_ * rate_;
      } else {
        v_mm_min = std::abs(p1_.position[a] - p0_.position[a]) / h * rate_ * 60.0;
      }
      bool fast = v_mm_min > ac.max_speed_mm_min * (1 + 1e-6);
      bool hard = a_mm_s2 > ac.max_accel_mm_s2 * (1 + 1e-6);
      if (!fast && !hard) continue;
      if (warnings_->size() >= kMaxWarnings) return;
      const Row& row = t_->rows[static_cast<std::size_t>(p1_.row)];
      warnings_->push_back(fmt::format(
          "{}:{}:{}: warning: at t = {:.6g} s the segment to this row (reference {:.6g}) needs {} "
          "{:.6g} mm/min and {:.6g} mm/s² (limits {:.6g}, {:.6g}): a value read during the run "
          "differs from the plan",
          t_->file, row.line, row.col, t_s, p1_.ref, kAxisLetters[a], v_mm_min, a_mm_s2,
          ac.max_speed_mm_min, ac.max_accel_mm_s2));
    }
  }

  static constexpr std::size_t kMaxWarnings = 100;

  void fire(const EffectivePoint& p, std::vector<MEvent>& events) const {
    for (std::int32_t r : {p.row, p.extra_row}) {
      if (r < 0) continue;
      const Row& row = t_->rows[static_cast<std::size_t>(r)];
      for (int code : row.m_codes) events.push_back({index_, row.line, code});
    }
  }

  const Table* t_;
  const Values* values_;
  bool cubic_;
  detail::Analyzer an_;
  std::uint8_t index_ = 0;
  EffectivePoint p0_, p1_, p2_;
  bool has_p1_ = false, has_p2_ = false;
  AxisVec m0_, m1_;  // tangents (per reference unit) at p0 and p1
  bool done_ = false;
  const MachineConfig* machine_ = nullptr;
  double rate_ = 0;
  std::vector<std::string>* warnings_ = nullptr;
};

}  // namespace

RunSummary run_tables(const TablePlan& plan,
                      const std::function<void(const TableSample&)>& on_sample) {
  for (const Diagnostic& d : plan.diagnostics) {
    if (d.severity == Diagnostic::Severity::kError) {
      throw InputError(d.file, d.line, d.col, d.message);
    }
  }
  const ReferenceSource& src = plan.options.reference;
  const double period_s = plan.machine.period_s;
  // slow_to_fit runs the reference at rate / slow_factor.
  const double ref_per_cycle = src.rate_per_s / plan.slow_factor * period_s;
  const bool master = plan.tables.front().ref_kind == RefKind::kAxis;
  const std::size_t master_axis = plan.tables.front().ref_axis;

  double ref = plan.start_ref;
  const double start_ref = ref;
  double master_pos = start_ref;
  std::vector<Cursor> cursors;
  cursors.reserve(plan.tables.size());
  TableSample s;
  s.m_codes.reserve(16);
  RunSummary sum;
  for (std::size_t i = 0; i < plan.tables.size(); ++i) {
    cursors.emplace_back(plan.tables[i], plan, start_ref);
    cursors.back().watch_limits(plan.machine, src.rate_per_s / plan.slow_factor, &sum.warnings);
    cursors.back().start(static_cast<std::uint8_t>(i), s.m_codes);
  }

  // The post-interpolation moving average ([motion] post_filter_s) over the last n_filter raw
  // positions of every axis but the master (the reference is not filtered): a velocity step
  // becomes a ramp over n_filter cycles. After the tables end it runs n_filter − 1 more cycles so
  // that the axes settle on the end point. Ring allocated here, before the first cycle.
  const std::size_t n_filter = post_filter_cycles(plan.machine);
  std::vector<AxisVec> ring(n_filter, plan.start_position);
  std::size_t ring_head = 0, settle_cycles = 0;
  bool tables_done = false;
  AxisVec raw = plan.start_position;
  AxisVec prev = plan.start_position;
  for (std::uint64_t k = 0;; ++k) {
    const double t_s = static_cast<double>(k) * period_s;
    if (k > 0) s.m_codes.clear();
    if (!tables_done) {
      if (k > 0) {
        // Forward-only reference: a master moving back holds the table where it is.
        if (src.position) {
          master_pos = src.position(t_s);  // once per cycle: the function may step a simulation
          ref = std::max(ref, master_pos);
        } else {
          ref = start_ref + static_cast<double>(k) * ref_per_cycle;
          master_pos = ref;
        }
      }
      raw = plan.start_position;
      if (master) raw[master_axis] = master_pos;
      tables_done = true;
      for (std::size_t i = 0; i < cursors.size(); ++i) {
        cursors[i].advance(ref, t_s, s.m_codes);
        cursors[i].evaluate(ref, raw);
        s.lines[i] = cursors[i].active_line();
        tables_done = tables_done && cursors[i].done();
      }
    } else {
      ++settle_cycles;
    }
    s.t_s = t_s;
    s.ref = ref;
    s.position = raw;
    if (n_filter > 1) {
      ring[ring_head] = raw;
      ring_head = (ring_head + 1) % n_filter;
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (master && a == master_axis) continue;
        double total = 0;
        for (const AxisVec& p : ring) total += p[a];
        s.position[a] = total / static_cast<double>(n_filter);
      }
    }
    s.line = s.lines[0];
    // Path speed of the linear axes over the last cycle (|Δxyz| / τ, mm/min).
    Vec3 d = s.position.xyz() - prev.xyz();
    s.feed_mm_min = k == 0 ? 0 : norm(d) / period_s * 60.0;
    prev = s.position;
    on_sample(s);
    ++sum.cycles;
    sum.duration_s = t_s;
    sum.end_ref = ref;
    if (tables_done && settle_cycles + 1 >= n_filter) break;
    // A clock or constant-rate source always reaches the end; a position function may stall.
    if (src.position && t_s >= plan.options.max_time_s) {
      sum.finished = false;
      sum.warnings.push_back(fmt::format(
          "stopped at t = {:.6g} s (max_time_s) before the tables ended: the reference stood at "
          "{:.6g}, the next control point is at {:.6g}",
          t_s, ref, cursors.front().end_ref()));
      break;
    }
  }
  return sum;
}

motion::Sample to_motion_sample(const TableSample& sample) {
  motion::Sample m;
  m.t_s = sample.t_s;
  m.line = sample.line;
  m.position = sample.position;
  m.path_position = sample.position;
  m.feed_mm_min = sample.feed_mm_min;
  if (!sample.m_codes.empty()) {
    m.aux_letter = 'M';
    m.aux_value = sample.m_codes.front().code;
  }
  return m;
}

}  // namespace cncore::tables
