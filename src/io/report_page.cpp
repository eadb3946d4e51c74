#include "io/report_page.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <iterator>

namespace cncore::io {

namespace assets {
std::string_view uplot_js();  // generated from the npm package (report_web/assets.cmake)
std::string_view uplot_css();
}  // namespace assets

namespace page {

namespace {

constexpr std::string_view kHelpers = R"JS(
window.cncore = (function () {
  const charts = [];
  const status = document.getElementById('cncore-status');
  function fmt(v, d) { return v == null ? '' : v.toFixed(d); }
  const width = () => Math.max(480, Math.min(1100, document.body.clientWidth - 40));
  // Every chart has a left and a right axis of fixed widths, so the charts of a page share
  // their time axis pixel for pixel; the cursor moves in all of them at once.
  function chart(id, title, series, data, axes, scales) {
    const el = document.getElementById(id);
    axes = (axes || [{}]).map((a, i) => (i === 0 ? a : Object.assign({ size: 70 }, a)));
    if (!axes.some((a, i) => i > 0 && a.side === 1)) {
      axes.push({ side: 1, scale: (axes[1] && axes[1].scale) || 'y', size: 70, label: '', grid: { show: false },
        ticks: { show: false }, values: (u, splits) => splits.map(() => '') });
    }
    const opts = {
      title: title, width: width(), height: 300, series: series, axes: axes, scales: scales,
      legend: { live: true }, cursor: { drag: { x: true, y: false }, sync: { key: 'cncore-time' } },
    };
    charts.push(new uPlot(opts, data, el));
  }
  // For the browser test: how many canvases were drawn on (uPlot draws in a later task).
  function check() {
    let inked = 0;
    const canvases = document.querySelectorAll('canvas');
    canvases.forEach((c) => {
      try {
        const g = c.getContext('2d'), img = g.getImageData(0, 0, c.width, c.height).data;
        let ink = 0;
        for (let i = 0; i < img.length; i += 4) if (img[i + 3] > 0 && (img[i] < 250 || img[i + 1] < 250 || img[i + 2] < 250)) ink++;
        if (ink > 100) inked++;
      } catch (e) { window.cncoreErrors.push('canvas: ' + e); }
    });
    status.dataset.charts = String(charts.length);
    status.dataset.canvases = String(canvases.length);
    status.dataset.inked = String(inked);
    status.dataset.errors = String(window.cncoreErrors.length);
    status.dataset.rendered = window.cncoreErrors.length === 0 ? 'ok' : 'errors';
    status.textContent = window.cncoreErrors.length === 0 ? '' : 'Errors: ' + window.cncoreErrors.join('; ');
  }
  return { charts: charts, fmt: fmt, width: width, chart: chart, check: check };
})();
)JS";

}  // namespace

std::string html_escape(std::string_view s) {
  std::string o;
  o.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

void put_number(std::string& o, double v) {
  if (!std::isfinite(v)) {
    o += "null";
  } else {
    fmt::format_to(std::back_inserter(o), "{:.6g}", v);
  }
}

std::string base64(std::string_view bytes) {
  static constexpr std::string_view kDigits =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string o;
  o.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    // Three bytes (zeros past the end) make four 6-bit digits; '=' for the missing ones.
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0U);
    }
    for (std::size_t k = 0; k < 4; ++k) {
      o += k <= n ? kDigits[(v >> (18 - 6 * k)) & 63U] : '=';
    }
  }
  return o;
}

std::string basename_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The look both reports share; each adds its own rules after it.
constexpr std::string_view kBaseStyle = R"CSS(
body { font: 14px/1.4 system-ui, sans-serif; margin: 20px; color: #222; max-width: 1160px; }
h1 { font-size: 20px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 22px 0 6px; }
table { border-collapse: collapse; } td, th { padding: 2px 10px 2px 0; text-align: left; vertical-align: top; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
code { background: #f4f4f4; padding: 0 3px; }
.warn { color: #a40; } #cncore-status { color: #c00; font-weight: bold; }
.note { color: #666; font-size: 12px; }
)CSS";

std::string head(const std::string& title, std::string_view style) {
  std::string o;
  o.reserve(assets::uplot_css().size() + style.size() + 1024);
  o += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  o += "<meta name=\"generator\" content=\"cncore\">\n";
  o += "<title>" + html_escape(title) + "</title>\n<style>";
  o += assets::uplot_css();
  o += kBaseStyle;
  o += style;
  o += "</style>\n";
  o += "<script>window.cncoreErrors=[];window.addEventListener('error',function(e){"
       "window.cncoreErrors.push(String(e.message));});"
       "(function(){var c=console.error;console.error=function(){"
       "window.cncoreErrors.push(Array.prototype.join.call(arguments,' '));"
       "c.apply(console,arguments);};})();</script>\n";
  o += "</head><body>\n";
  return o;
}

std::string tail(const std::string& data_script, std::string_view page_script) {
  std::string o;
  o.reserve(assets::uplot_js().size() + kHelpers.size() + data_script.size() + page_script.size() +
            128);
  o += "<script>";
  o += assets::uplot_js();
  o += "</script>\n<script>";
  o += kHelpers;
  o += "</script>\n<script>";
  o += data_script;
  o += "</script>\n<script>";
  o += page_script;
  o += "</script>\n</body></html>\n";
  return o;
}

}  // namespace page
}  // namespace cncore::io
