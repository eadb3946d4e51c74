#include "io/report_table.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "io/buckets.hpp"
#include "io/report_page.hpp"

namespace cncore::io {

using page::html_escape;
using page::js_array;

void MinMax::merge(const MinMax& later) {
  if (std::isnan(later.min)) return;
  if (std::isnan(min)) {
    *this = later;
    return;
  }
  // Drawing order of the merged extremes: the earlier one first.
  const bool lower = later.min<min, higher = later.max> max;
  min_first = lower ? (higher ? later.min_first : false) : (higher ? true : min_first);
  min = std::min(min, later.min);
  max = std::max(max, later.max);
}

void MinMax::add(double v) {
  if (std::isnan(v)) return;
  merge(MinMax{v, v, true});
}

TableReportObserver::TableReportObserver(const MachineConfig& machine, std::uint32_t axis_mask,
                                         TableReportOptions options)
    : axis_mask_(0), options_(options), diff_(machine) {
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (((axis_mask >> i) & 1U) != 0 && machine.axes[i].enabled) axis_mask_ |= 1U << i;
  }
  options_.buckets = std::max<std::size_t>(options_.buckets, 16);
  buckets_.reserve(2 * options_.buckets);
  events_.reserve(options_.m_events);
}

void TableReportObserver::add_m_code(double t_s, std::size_t table, std::uint32_t line, int code,
                                     double ref) {
  ++m_code_count_;
  ++pending_m_;
  if (events_.size() < options_.m_events) events_.push_back({t_s, table, line, code, ref});
}

void TableReportObserver::on_sample(const motion::Sample& s) {
  ++samples_;
  const CycleDifferences& d = diff_.update(s.t_s, s.position);
  TableReportBucket one;
  one.t_first_s = one.t_last_s = s.t_s;
  one.samples = 1;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (((axis_mask_ >> i) & 1U) == 0) continue;
    one.position[i].add(s.position[i]);
    // |v|·60 per minute: the summary's max_axis_speed_mm_min is the largest of these.
    if (d.moved) one.speed[i].add(std::fabs(d.vel[i]) * 60);
    if (d.accel) one.accel[i].add(std::fabs(d.acc[i]));
  }
  one.ref.add(s.ref);
  one.m_codes = pending_m_;
  pending_m_ = 0;
  add_to_bucket(one);
}

void TableReportObserver::add_to_bucket(const TableReportBucket& s) {
  auto merge = [](TableReportBucket& a, const TableReportBucket& b) {
    a.t_last_s = b.t_last_s;
    a.samples += b.samples;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      a.position[i].merge(b.position[i]);
      a.speed[i].merge(b.speed[i]);
      a.accel[i].merge(b.accel[i]);
    }
    a.ref.merge(b.ref);
    a.m_codes += b.m_codes;
  };
  add_to_buckets(buckets_, bucket_samples_, options_.buckets, s, merge);
}

std::size_t TableReportObserver::memory_bytes() const {
  return buckets_.capacity() * sizeof(TableReportBucket) +
         events_.capacity() * sizeof(TableReportEvent);
}

// ---------------------------------------------------------------------------------------------

namespace {

// Speeds and accelerations of every charted axis with its limit (same colour, dashed); the
// reference value with the M codes as points; the axis positions.
constexpr std::string_view kPageScript = R"JS(
(function () {
  const D = window.CNCORE_DATA;
  const { fmt, chart } = window.cncore;
  const T = D.t;
  const colours = ['#1f77b4', '#ff7f0e', '#2ca02c', '#9467bd', '#8c564b', '#e377c2'];
  function axisChart(id, title, key, limitKey, unitKey, digits) {
    const s = [{ label: 't (s)', value: (u, v) => fmt(v, 3) }], d = [T];
    D.axes.forEach((a, k) => {
      const c = colours[k % colours.length];
      s.push({ label: a.name + ' (' + a[unitKey] + ')', stroke: c, width: 1.5, value: (u, v) => fmt(v, digits) });
      d.push(a[key]);
      if (limitKey) {
        const L = a[limitKey];
        s.push({ label: a.name + ' limit', stroke: c, width: 1, dash: [2, 3], value: (u, v) => fmt(v, 0) });
        d.push(T.map(() => L));
      }
    });
    chart(id, title, s, d, [{}, { size: 70 }], { x: { time: false } });
  }
  axisChart('speed-chart', 'Axis speeds', 'speed', 'speed_limit', 'speed_unit', 1);
  axisChart('accel-chart', 'Axis accelerations', 'accel', 'accel_limit', 'accel_unit', 0);
  chart('ref-chart', 'Reference value', [
    { label: 't (s)', value: (u, v) => fmt(v, 3) },
    { label: D.ref_name + ' (' + D.ref_unit + ')', stroke: '#1f77b4', width: 1.5, value: (u, v) => fmt(v, 3) },
    { label: 'M code fired', stroke: '#d62728', fill: '#d62728', paths: () => null,
      points: { show: true, size: 9, space: 0, stroke: '#d62728', fill: '#d62728' }, value: (u, v) => v == null ? '' : 'M' },
  ], [T, D.ref, D.m], [{}, { label: D.ref_unit, size: 70 }], { x: { time: false } });
  axisChart('pos-chart', 'Axis positions', 'position', null, 'pos_unit', 3);
  // The path in the plane of the first two axes: the second across, the first up (Z across
  // and X up on a lathe), to one scale; the start marked by a circle.
  const cv = document.getElementById('plane-canvas');
  if (D.axes.length >= 2) {
    document.getElementById('plane-section').hidden = false;
    const V = D.axes[0].position, U = D.axes[1].position;
    const w = Math.min(window.cncore.width(), 900), h = Math.round(w * 0.6), pad = 34;
    cv.width = w; cv.height = h;
    const g = cv.getContext('2d');
    g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
    let u0 = Infinity, u1 = -Infinity, v0 = Infinity, v1 = -Infinity;
    for (let i = 0; i < U.length; i++) {
      if (U[i] == null || V[i] == null) continue;
      u0 = Math.min(u0, U[i]); u1 = Math.max(u1, U[i]); v0 = Math.min(v0, V[i]); v1 = Math.max(v1, V[i]);
    }
    const k = Math.min((w - 2 * pad) / Math.max(u1 - u0, 1e-9), (h - 2 * pad) / Math.max(v1 - v0, 1e-9));
    const ou = pad + (w - 2 * pad - (u1 - u0) * k) / 2, ov = pad + (h - 2 * pad - (v1 - v0) * k) / 2;
    const X = (u) => ou + (u - u0) * k, Y = (v) => h - ov - (v - v0) * k;
    g.strokeStyle = '#1f77b4'; g.lineWidth = 1.5; g.beginPath();
    let first = true;
    for (let i = 0; i < U.length; i++) {
      if (U[i] == null || V[i] == null) continue;
      if (first) { g.moveTo(X(U[i]), Y(V[i])); first = false; } else g.lineTo(X(U[i]), Y(V[i]));
    }
    g.stroke();
    if (U.length > 0) { g.beginPath(); g.arc(X(U[0]), Y(V[0]), 5, 0, 2 * Math.PI); g.stroke(); }
    g.fillStyle = '#000'; g.font = '12px sans-serif';
    const a = D.axes;
    g.fillText(a[1].name + ' ' + u0.toFixed(2) + ' … ' + u1.toFixed(2) + ' ' + a[1].pos_unit + ' (across),  ' +
      a[0].name + ' ' + v0.toFixed(2) + ' … ' + v1.toFixed(2) + ' ' + a[0].pos_unit + ' (up)', pad, h - 10);
  }
  // For the browser test (uPlot draws in a later task).
  setTimeout(window.cncore.check, 50);
})();
)JS";

constexpr std::string_view kStyle = R"CSS(
table.events td, table.events th { border-bottom: 1px solid #ddd; padding: 3px 8px; }
)CSS";

}  // namespace

// Size: the table report's page in the order it reads: header, figures, the axes' plots and the
// path, the events; each part is a few lines of page text around data built above.
std::string render_table_report_html(const TableReportObserver& report, const Summary& summary,
                                     const MachineConfig& machine, const TableReportInput& input) {
  std::string names;
  for (const std::string& t : input.tables) {
    names += (names.empty() ? "" : ", ") + page::basename_of(t);
  }
  const std::string title = input.title.empty() ? "cncore table report: " + names : input.title;
  const auto& bk = report.buckets();
  std::vector<std::size_t> axes;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (((report.axis_mask() >> i) & 1U) != 0) axes.push_back(i);
  }

  // Two points per bucket: its minimum and maximum in the order they came (extremes drawn).
  const std::size_t n = bk.size() * 2;
  auto ordered = [&](std::size_t i, const MinMax& m) {
    return (i % 2 == 0) == m.min_first ? m.min : m.max;
  };
  std::string data = "window.CNCORE_DATA={";
  data += "\"t\":" + js_array(n, [&](std::size_t i) {
            const TableReportBucket& b = bk[i / 2];
            return i % 2 == 0 ? b.t_first_s : std::max(b.t_last_s, b.t_first_s);
          });
  data += ",\"ref\":" + js_array(n, [&](std::size_t i) { return ordered(i, bk[i / 2].ref); });
  // A marker at the first point of every bucket in which an M code fired.
  data += ",\"m\":" + js_array(n, [&](std::size_t i) {
            const TableReportBucket& b = bk[i / 2];
            return i % 2 == 0 && b.m_codes > 0 ? ordered(i, b.ref) : NAN;
          });
  data += fmt::format(",\"ref_name\":\"{}\",\"ref_unit\":\"{}\",\"axes\":[",
                      html_escape(input.ref_name), html_escape(input.ref_unit));
  for (std::size_t k = 0; k < axes.size(); ++k) {
    const std::size_t a = axes[k];
    const AxisConfig& ax = machine.axes[a];
    const char* u = ax.rotary ? "deg" : "mm";
    data += fmt::format(
        "{}{{\"name\":\"{}\",\"speed_unit\":\"{}/min\",\"accel_unit\":\"{}/s²\",\"pos_unit\":"
        "\"{}\",\"speed_limit\":{},\"accel_limit\":{}",
        k > 0 ? "," : "", kAxisLetters[a], u, u, u, ax.max_speed_mm_min, ax.max_accel_mm_s2);
    data +=
        ",\"speed\":" + js_array(n, [&](std::size_t i) { return ordered(i, bk[i / 2].speed[a]); });
    data +=
        ",\"accel\":" + js_array(n, [&](std::size_t i) { return ordered(i, bk[i / 2].accel[a]); });
    data += ",\"position\":" +
            js_array(n, [&](std::size_t i) { return ordered(i, bk[i / 2].position[a]); });
    data += "}";
  }
  data += "]};";

  std::string o = page::head(title, kStyle);
  o.reserve(o.size() + data.size() + 40000);
  o += "<h1 id=\"title\">" + html_escape(title) + "</h1>\n";
  std::string files;
  for (const std::string& t : input.tables) {
    files += (files.empty() ? "" : ", ") + ("<code>" + html_escape(t) + "</code>");
  }
  o += fmt::format("<div class=\"note\">tables {}, machine {}</div>\n", files,
                   html_escape(machine.name));
  o += page::kStatusDiv;

  o += "<h2>Summary</h2>\n<table id=\"summary\">\n";
  auto row = [&](const std::string& key, const std::string& label, double value,
                 const std::string& text) {
    o += fmt::format("<tr><th>{}</th><td id=\"s-{}\" data-value=\"{:.9g}\">{}</td></tr>\n", label,
                     key, value, text);
  };
  row("cycle_time_s", "cycle time", summary.cycle_time_s,
      fmt::format("{:.3f} s{}", summary.cycle_time_s,
                  input.finished ? "" : " — stopped before the end"));
  row("cycles", "cycles", static_cast<double>(summary.cycles), fmt::format("{}", summary.cycles));
  row("end_ref", "reference", input.end_ref,
      fmt::format("{} {:.6g} … {:.6g} {}", html_escape(input.ref_name), input.start_ref,
                  input.end_ref, html_escape(input.ref_unit)));
  if (input.slow_factor > 1) {
    row("slow_factor", "slowed", input.slow_factor,
        fmt::format("reference runs {:.4g} times slower to fit the axis limits",
                    input.slow_factor));
  }
  for (const std::size_t a : axes) {
    const AxisConfig& ax = machine.axes[a];
    const char* u = ax.rotary ? "deg" : "mm";
    const char letter = kAxisLetters[a];
    row(fmt::format("max_speed_{}", letter), fmt::format("max speed {}", letter),
        summary.max_axis_speed_mm_min[a],
        fmt::format("{:.1f} {}/min (limit {:.0f})", summary.max_axis_speed_mm_min[a], u,
                    ax.max_speed_mm_min));
    row(fmt::format("max_accel_{}", letter), fmt::format("max acceleration {}", letter),
        summary.max_axis_accel_mm_s2[a],
        fmt::format("{:.1f} {}/s² (limit {:.0f})", summary.max_axis_accel_mm_s2[a], u,
                    ax.max_accel_mm_s2));
  }
  row("m_codes", "M codes fired", static_cast<double>(report.m_code_count()),
      fmt::format("{}", report.m_code_count()));
  for (const std::string& w : summary.warnings) {
    o += "<tr><th>warning</th><td class=\"warn\">" + html_escape(w) + "</td></tr>\n";
  }
  for (const std::string& w : input.warnings) {
    o += "<tr><th>warning</th><td class=\"warn\">" + html_escape(w) + "</td></tr>\n";
  }
  o += "</table>\n";

  o += "<h2>Axis speeds</h2>\n<div id=\"speed-chart\"></div>\n";
  o += "<h2>Axis accelerations</h2>\n<div id=\"accel-chart\"></div>\n";
  o += "<h2>Reference value and M codes</h2>\n<div id=\"ref-chart\"></div>\n";
  o += "<h2>Axis positions</h2>\n<div id=\"pos-chart\"></div>\n";
  o += "<section id=\"plane-section\" hidden><h2>The path in the plane of the first two axes"
       "</h2>\n<canvas id=\"plane-canvas\"></canvas></section>\n";
  o += fmt::format(
      "<div class=\"note\">{} samples shown as {} buckets of {}+ cycles each (minimum and "
      "maximum of every bucket drawn). Speeds and accelerations are magnitudes, by finite "
      "differences of the set-points as in the summary; dashed: the axis limits.</div>\n",
      report.samples(), bk.size(), bk.empty() ? 0 : bk.front().samples);

  const auto& ev = report.events();
  o += fmt::format("<h2>M codes ({} fired{})</h2>\n", report.m_code_count(),
                   ev.size() < report.m_code_count()
                       ? fmt::format(", the first {} listed", ev.size())
                       : std::string());
  o += "<table class=\"events\" id=\"m-codes\"><tr><th>#</th><th class=\"num\">t (s)</th>"
       "<th>M code</th><th>table</th><th class=\"num\">line</th><th class=\"num\">reference</th>"
       "</tr>\n";
  for (std::size_t i = 0; i < ev.size(); ++i) {
    const TableReportEvent& e = ev[i];
    const std::string table =
        e.table < input.tables.size() ? page::basename_of(input.tables[e.table]) : "";
    o += fmt::format(
        "<tr><td>{}</td><td class=\"num\">{:.3f}</td><td>M{}</td><td>{}</td><td "
        "class=\"num\">{}</td><td class=\"num\">{:.6g}</td></tr>\n",
        i + 1, e.t_s, e.code, html_escape(table), e.line, e.ref);
  }
  o += "</table>\n";
  o += "<div class=\"note\">Charts: uPlot (MIT).</div>\n";
  o += page::tail(data, kPageScript);
  return o;
}

}  // namespace cncore::io
