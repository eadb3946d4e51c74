// The page of `cncore run --report`: the summary, the time lost and its causes, speed and
// acceleration against time, the path in three views coloured by the cutting speed, and the
// slowest cutting lines and rapids with the reason they are slow.
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <string_view>

#include "io/report.hpp"
#include "io/report_page.hpp"

namespace cncore::io {

namespace {

using page::html_escape;
using page::js_array;

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
  // The speed axis runs to the fastest cutting speed (rapids run off the top; the legend and
  // a zoom show them), so that the cutting feeds are told apart.
  const vtop = D.vmax_all > D.vmax * 1.2 && D.vmax > 0 ? D.vmax * 1.15 : null;
  chart('speed-chart', 'Path speed', [
    { label: 't (s)', value: (u, v) => fmt(v, 3) },
    { label: 'speed (mm/min)', stroke: '#1f77b4', width: 1.5, value: (u, v) => fmt(v, 0) },
    { label: 'programmed feed (mm/min)', stroke: '#2ca02c', width: 1, dash: [6, 3], value: (u, v) => fmt(v, 0) },
    { label: 'machine limit (mm/min)', stroke: '#d62728', width: 1, dash: [2, 3], value: (u, v) => fmt(v, 0) },
    { label: 'override (%)', stroke: '#9467bd', width: 1, scale: 'pct', value: (u, v) => fmt(v, 0) },
  ], [T, D.speed, D.feed, D.limit, D.override], [
    {}, { label: 'mm/min' }, { side: 1, scale: 'pct', label: '%', grid: { show: false } },
  ], { x: { time: false }, y: vtop ? { range: [0, vtop] } : {}, pct: { range: [0, Math.max(150, D.override_max * 1.1)] } });
  const A = D.accel_limit;
  chart('accel-chart', 'Acceleration', [
    { label: 't (s)', value: (u, v) => fmt(v, 3) },
    { label: 'tangential (mm/s²)', stroke: '#ff7f0e', width: 1.5, value: (u, v) => fmt(v, 0) },
    { label: 'resultant incl. normal (mm/s²)', stroke: '#8c564b', width: 1, value: (u, v) => fmt(v, 0) },
    { label: '+limit', stroke: '#d62728', dash: [2, 3], width: 1, value: (u, v) => fmt(v, 0) },
    { label: '−limit', stroke: '#d62728', dash: [2, 3], width: 1, value: (u, v) => fmt(v, 0) },
  ], [T, D.accel, D.path_accel, T.map(() => A), T.map(() => -A)], [
    {}, { label: 'mm/s²' },
  ], { x: { time: false } });
  if (D.correction || D.load) {
    const s = [{ label: 't (s)', value: (u, v) => fmt(v, 3) }], d = [T];
    if (D.correction) { s.push({ label: 'correction (×)', stroke: '#17becf', scale: 'k', value: (u, v) => fmt(v, 3) }); d.push(D.correction); }
    if (D.load) {
      s.push({ label: 'load (%)', stroke: '#e377c2', scale: '%', value: (u, v) => fmt(v, 1) }); d.push(D.load);
      s.push({ label: 'load target (%)', stroke: '#7f7f7f', dash: [4, 4], scale: '%', value: (u, v) => fmt(v, 1) }); d.push(D.load_target);
    }
    const axes = [{}];
    if (D.correction) axes.push({ scale: 'k', label: '×' });
    if (D.load) axes.push({ scale: '%', label: '%', side: D.correction ? 1 : 3, grid: { show: !D.correction } });
    document.getElementById('extra-section').hidden = false;
    chart('extra-chart', 'Correction and load', s, d, axes, { x: { time: false } });
  }

  // Time lost by cause: horizontal bars, the seconds and the share of the total written beside.
  (function () {
    const cv = document.getElementById('loss-canvas'), L = D.losses;
    const rowH = 26, left = 130, right = 170;
    cv.width = Math.min(width() - 260, 760); cv.height = rowH * L.length + 16;
    const g = cv.getContext('2d');
    g.fillStyle = '#fff'; g.fillRect(0, 0, cv.width, cv.height);
    const top = Math.max(1e-9, ...L.map((c) => Math.abs(c.s)));
    const total = L.reduce((a, c) => a + c.s, 0);
    g.font = '13px sans-serif'; g.textBaseline = 'middle';
    L.forEach((c, i) => {
      const y = 8 + i * rowH, w = (cv.width - left - right) * Math.abs(c.s) / top;
      g.fillStyle = '#222'; g.textAlign = 'right'; g.fillText(c.name, left - 8, y + rowH / 2);
      g.fillStyle = c.s < 0 ? '#2ca02c' : '#d62728';
      g.fillRect(left, y + 4, Math.max(w, c.s !== 0 ? 1 : 0), rowH - 8);
      g.fillStyle = '#222'; g.textAlign = 'left';
      const pct = total > 0 ? ' (' + (100 * c.s / total).toFixed(1) + ' %)' : '';
      g.fillText(c.s.toFixed(3) + ' s' + pct, left + w + 6, y + rowH / 2);
    });
  })();

  // Path views of the servo set-points: top (X/Y), front (X/Z), side (Y/Z), each to its own
  // scale, coloured by speed from 0 to the fastest cutting speed (blue slow → red fast; faster
  // is red too); rapid moves dashed grey.
  const P = D.path, n = P.x.length;
  const vmax = Math.max(D.vmax, 1);
  const colour = (v) => 'hsl(' + Math.round(240 * (1 - Math.min(v / vmax, 1))) + ',85%,45%)';
  // A view w wide and as high as its aspect needs (at most maxH, at least 140 px).
  function view(id, U, V, uName, vName, w, maxH, marks, bar) {
    const cv = document.getElementById(id);
    let u0 = Infinity, u1 = -Infinity, v0 = Infinity, v1 = -Infinity;
    for (let i = 0; i < n; i++) {
      u0 = Math.min(u0, U[i]); u1 = Math.max(u1, U[i]); v0 = Math.min(v0, V[i]); v1 = Math.max(v1, V[i]);
    }
    const pad = 30, pw = w - 2 * pad - (bar ? 70 : 0);
    const aspect = n > 0 ? (v1 - v0) / Math.max(u1 - u0, 1e-9) : 0.5;
    const h = Math.round(Math.max(140, Math.min(maxH, pw * aspect + 2 * pad + 14)));
    const ph = h - 2 * pad - 14;
    cv.width = w; cv.height = h;
    const g = cv.getContext('2d');
    g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
    if (n === 0) return;
    const k = Math.min(pw / Math.max(u1 - u0, 1e-9), ph / Math.max(v1 - v0, 1e-9));
    // Centred in the plot area (a flat view is a line across its middle).
    const ou = pad + (pw - (u1 - u0) * k) / 2, ov = pad + (ph - (v1 - v0) * k) / 2;
    const X = (u) => ou + (u - u0) * k, Y = (v) => h - 14 - ov - (v - v0) * k;
    g.lineWidth = 1.5; g.lineCap = 'round';
    for (let i = 1; i < n; i++) {
      g.beginPath();
      g.strokeStyle = P.rapid[i] ? '#bbb' : colour(P.v[i]);
      g.setLineDash(P.rapid[i] ? [4, 3] : []);
      g.moveTo(X(U[i - 1]), Y(V[i - 1])); g.lineTo(X(U[i]), Y(V[i]));
      g.stroke();
    }
    g.setLineDash([]);
    g.font = '12px sans-serif';
    g.fillStyle = '#000';
    g.fillText(uName + ' ' + u0.toFixed(1) + ' … ' + u1.toFixed(1) + ' mm,  ' + vName + ' ' + v0.toFixed(1) + ' … ' + v1.toFixed(1) + ' mm', pad, h - 8);
    if (marks) label(g, marks.map((m) => [X(m.u), Y(m.v)]), w, h);
    if (bar) {
      const bx = w - 50;
      for (let j = 0; j < ph; j++) { g.fillStyle = colour(vmax * (1 - j / ph)); g.fillRect(bx, pad + j, 14, 1); }
      g.fillStyle = '#000';
      g.fillText(Math.round(vmax) + '', bx - 4, pad - 6);
      g.fillText('0 mm/min', bx - 20, pad + ph + 14);
    }
  }
  // Numbered circles at the slow spots; each number goes to the first place around its circle
  // (then farther out, with a leader line) where it overlaps no other number or circle.
  function label(g, pts, w, h) {
    const boxes = pts.map(([x, y]) => [x - 6, y - 6, x + 6, y + 6]);
    const hit = (b) => b[0] < 0 || b[1] < 0 || b[2] > w || b[3] > h ||
      boxes.some((o) => b[0] < o[2] && o[0] < b[2] && b[1] < o[3] && o[1] < b[3]);
    pts.forEach(([x, y]) => {
      g.beginPath(); g.strokeStyle = '#000'; g.arc(x, y, 6, 0, 2 * Math.PI); g.stroke();
    });
    pts.forEach(([x, y], i) => {
      const text = String(i + 1), tw = g.measureText(text).width, th = 12;
      let at = null;
      for (let r = 9; r <= 90 && !at; r += 9) {
        for (let a = 0; a < 16 && !at; a++) {
          const ang = -Math.PI / 4 + a * Math.PI / 8;
          const cx = x + r * Math.cos(ang), cy = y + r * Math.sin(ang);
          const b = [cx - tw / 2 - 1, cy - th / 2, cx + tw / 2 + 1, cy + th / 2];
          if (!hit(b)) at = [cx, cy, b, r];
        }
      }
      if (!at) at = [x + 9, y - 9, [x + 3, y - 15, x + 15, y - 3], 9];
      boxes.push(at[2]);
      if (at[3] > 12) {
        g.beginPath(); g.strokeStyle = '#888'; g.moveTo(x, y); g.lineTo(at[0], at[1]); g.stroke();
      }
      g.fillStyle = '#000'; g.textAlign = 'center'; g.textBaseline = 'middle';
      g.fillText(text, at[0], at[1]);
      g.textAlign = 'start'; g.textBaseline = 'alphabetic';
    });
  }
  const W = width();
  view('path-canvas', P.x, P.y, 'X', 'Y', W, Math.round(W * 0.62),
    D.slow.map((s) => ({ u: s.x, v: s.y })), true);
  const half = Math.floor((W - 10) / 2);
  view('front-canvas', P.x, P.z, 'X', 'Z', half, Math.round(half * 0.6), null, false);
  view('side-canvas', P.y, P.z, 'Y', 'Z', half, Math.round(half * 0.6), null, false);

  // For the browser test (uPlot draws in a later task).
  setTimeout(window.cncore.check, 50);
})();
)JS";

constexpr std::string_view kStyle = R"CSS(
table.slow td, table.slow th { border-bottom: 1px solid #ddd; padding: 3px 8px; }
table.slow code { white-space: pre; }
.views { display: flex; gap: 10px; }
)CSS";

// window.CNCORE_DATA: the time series (two points per bucket: its minimum and maximum, in the
// order they came, so the extremes of every bucket are drawn), the path, the causes of the time
// lost and the slow spots' places.
std::string page_data(const ReportObserver& report, const MachineConfig& machine,
                      const std::vector<ReportSlowSpot>& slow) {
  const auto& bk = report.buckets();
  const std::size_t n = bk.size() * 2;
  auto at_t = [&](std::size_t i) {
    const ReportBucket& b = bk[i / 2];
    return i % 2 == 0 ? b.t_first_s : std::max(b.t_last_s, b.t_first_s);
  };
  auto ordered = [&](std::size_t i, double lo, double hi, bool lo_first) {
    return (i % 2 == 0) == lo_first ? lo : hi;
  };
  double override_max = 100, vmax_all = 0;
  for (const ReportBucket& b : bk) {
    override_max = std::max(override_max, b.override_max_pct);
    vmax_all = std::max(vmax_all, b.speed_max_mm_min);
  }
  // The colour scale and the speed axis: the cutting moves' own range (all moves if none cut).
  const double vmax =
      report.cutting_speed_max_mm_min() > 0 ? report.cutting_speed_max_mm_min() : vmax_all;
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
  data += fmt::format(R"(,"accel_limit":{},"override_max":{},"vmax":{},"vmax_all":{})",
                      machine.max_accel_mm_s2, override_max, vmax, vmax_all);
  const auto& p = report.path();
  data += R"(,"path":{"x":)" + js_array(p.size(), [&](std::size_t i) { return p[i].x_mm; });
  data += ",\"y\":" + js_array(p.size(), [&](std::size_t i) { return p[i].y_mm; });
  data += ",\"z\":" + js_array(p.size(), [&](std::size_t i) { return p[i].z_mm; });
  data += ",\"v\":" + js_array(p.size(), [&](std::size_t i) { return double{p[i].speed_mm_min}; });
  data += ",\"rapid\":" + js_array(p.size(), [&](std::size_t i) { return p[i].rapid ? 1.0 : 0.0; });
  data += "},\"losses\":[";
  const ReportLosses& losses = report.losses();
  for (std::size_t c = 0; c < kLossCauses; ++c) {
    data += fmt::format(R"({}{{"name":"{}","s":{:.6g}}})", c ? "," : "",
                        loss_cause_name(static_cast<LossCause>(c)), losses.cause_s[c]);
  }
  data += "],\"slow\":[";
  for (std::size_t i = 0; i < slow.size(); ++i) {
    data += fmt::format(R"({}{{"x":{:.6g},"y":{:.6g},"line":{}}})", i ? "," : "", slow[i].x_mm,
                        slow[i].y_mm, slow[i].line);
  }
  data += "]};";
  return data;
}

void summary_table(std::string& o, const ReportObserver& report, const Summary& summary,
                   const MachineConfig& machine) {
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
  const ReportLosses& l = report.losses();
  row("time_lost_s", "time lost", summary.time_lost_s,
      fmt::format("{:.3f} s against F × override: {:.3f} s cutting, {:.3f} s on rapids",
                  summary.time_lost_s, l.cutting_s, l.rapid_s));
  row("time_lost_program_s", "time lost against F as written", l.total_s(),
      fmt::format("{:.3f} s (the causes below)", l.total_s()));
  o += fmt::format("<tr><th>mode</th><td id=\"s-mode\">{}</td></tr>\n", html_escape(summary.mode));
  for (const std::string& w : summary.warnings) {
    o += "<tr><th>warning</th><td class=\"warn\">" + html_escape(w) + "</td></tr>\n";
  }
  o += "</table>\n";
}

void losses_section(std::string& o, const ReportLosses& l) {
  o += "<h2>Time lost and what caused it</h2>\n<div class=\"views\"><canvas id=\"loss-canvas\">"
       "</canvas>\n<table id=\"losses\" class=\"slow\"><tr><th>cause</th><th class=\"num\">time "
       "lost (s)</th></tr>\n";
  for (std::size_t c = 0; c < kLossCauses; ++c) {
    o += fmt::format("<tr><td>{}</td><td class=\"num\" data-value=\"{:.9g}\">{:.3f}</td></tr>\n",
                     loss_cause_name(static_cast<LossCause>(c)), l.cause_s[c], l.cause_s[c]);
  }
  o += fmt::format(
      "<tr><th>total</th><th class=\"num\" id=\"loss-total\" data-value=\"{:.9g}\">{:.3f}</th>"
      "</tr></table></div>\n",
      l.total_s(), l.total_s());
  o += "<div class=\"note\">Against F as written: <i>feed limit</i> is the time the machine's "
       "maximum feed adds, <i>override</i> what the feed override adds (negative: saves); the "
       "rest is the time lost against F × override, each cycle's share of it given to the "
       "arc, stop, corner or chain of short segments that slows the tool there, else to "
       "<i>acceleration</i> (see docs/reports.md).</div>\n";
}

void slow_table(std::string& o, const char* id, const std::vector<ReportSlowSpot>& slow,
                const std::map<std::uint32_t, std::string>& texts, const ReportObserver& report) {
  o += fmt::format(
      "<table class=\"slow\" id=\"{}\"><tr><th>#</th><th class=\"num\">line</th>"
      "<th>program</th><th class=\"num\">time lost (s)</th><th class=\"num\">min speed "
      "(mm/min)</th><th class=\"num\">asked (mm/min)</th><th class=\"num\">visits</th>",
      id);
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
}

// The cutting simulation's height map as an inlined PNG, with its colour scale beside it.
void heightmap_section(std::string& o, const ReportHeightMap& map) {
  if (map.png.empty()) return;
  std::string stops;
  for (const std::string& c : map.scale) stops += (stops.empty() ? "" : ",") + c;
  o += "<h2>Cutting simulation: the stock at the end (top view, +Y up)</h2>\n"
       "<div class=\"views\"><img id=\"heightmap\" alt=\"height map\" style=\"max-width:"
       "calc(100% - 120px); max-height:640px; image-rendering:pixelated\" src=\"data:image/png;"
       "base64,";
  o += page::base64(map.png);
  o += fmt::format(
      "\"><div style=\"display:flex; gap:6px\"><div style=\"width:16px; height:240px; "
      "background:linear-gradient(to top,{})\"></div><div style=\"display:flex; "
      "flex-direction:column; justify-content:space-between; height:240px\" class=\"note\">"
      "<span id=\"heightmap-top\">Z {:.3f} mm</span><span id=\"heightmap-bottom\">Z {:.3f} mm"
      "</span></div></div></div>\n",
      stops, map.top_z_mm, map.bottom_z_mm);
  o += "<div class=\"note\">Colour by height from the stock bottom to its top, shaded from the "
       "north-west (docs/cutting-simulation.md).</div>\n";
}

}  // namespace

std::string render_report_html(const ReportObserver& report, const Summary& summary,
                               const MachineConfig& machine, const ReportInput& input) {
  const std::string title =
      input.title.empty() ? "cncore report: " + page::basename_of(input.program) : input.title;
  const std::vector<ReportSlowSpot> slow = report.slowest();
  const std::vector<ReportSlowSpot> rapids = report.slowest_rapids();
  const std::string data = page_data(report, machine, slow);
  std::vector<std::uint32_t> lines;
  lines.reserve(slow.size() + rapids.size());
  for (const ReportSlowSpot& s : slow) lines.push_back(s.line);
  for (const ReportSlowSpot& s : rapids) lines.push_back(s.line);
  const auto texts = program_lines(input.program, lines);
  const auto& bk = report.buckets();

  std::string o;
  o.reserve(data.size() + 120000);
  o += page::head(title, kStyle);
  o += "<h1 id=\"title\">" + html_escape(title) + "</h1>\n";
  o += fmt::format("<div class=\"note\">program <code>{}</code>, machine {}</div>\n",
                   html_escape(input.program), html_escape(machine.name));
  o += page::kStatusDiv;
  summary_table(o, report, summary, machine);
  losses_section(o, report.losses());

  o += "<h2>Speed</h2>\n<div id=\"speed-chart\"></div>\n";
  o += "<h2>Acceleration</h2>\n<div id=\"accel-chart\"></div>\n";
  o += "<section id=\"extra-section\" hidden><h2>Correction and load</h2>"
       "<div id=\"extra-chart\"></div></section>\n";
  o += fmt::format(
      "<div class=\"note\">{} samples shown as {} buckets of {}+ cycles each (minimum and "
      "maximum of every bucket drawn). The speed axis runs to the fastest cutting speed.</div>\n",
      report.samples(), bk.size(), bk.empty() ? 0 : bk.front().samples);
  o += "<h2>The path: top (X/Y), front (X/Z) and side (Y/Z) views, coloured by speed</h2>\n"
       "<canvas id=\"path-canvas\"></canvas>\n<div class=\"views\"><canvas id=\"front-canvas\">"
       "</canvas><canvas id=\"side-canvas\"></canvas></div>\n";
  o += "<div class=\"note\">Blue slow, red at the fastest cutting speed (and above); rapid moves "
       "dashed grey; numbered circles: the slowest cutting lines below.</div>\n";

  heightmap_section(o, input.heightmap);

  o += fmt::format("<h2>The {} slowest cutting lines</h2>\n", slow.size());
  slow_table(o, "slowest", slow, texts, report);
  o += fmt::format("<h2>Rapids (G0): {:.3f} s lost, the {} slowest</h2>\n", report.losses().rapid_s,
                   rapids.size());
  slow_table(o, "slowest-rapids", rapids, texts, report);
  o += "<div class=\"note\">Time lost: time on the line minus the time at the asked speed "
       "(programmed feed × override, capped by the machine), the summary's own figure: a cycle "
       "that passes several lines gives each its share. Charts: uPlot (MIT).</div>\n";

  o += page::tail(data, kPageScript);
  return o;
}

}  // namespace cncore::io
