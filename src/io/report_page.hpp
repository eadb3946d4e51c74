// Pieces the HTML pages of `cncore run --report`, `cncore table --report` and
// `cncore estimate --report` share: escaping, number arrays for the page's data, the page head
// with the inlined chart library and the error hooks, and the script that draws uPlot charts and
// records for the browser test how many canvases were drawn on.
#pragma once

#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>

namespace cncore::io::page {

std::string html_escape(std::string_view s);

// Numbers for the page: 6 significant digits, null for NaN/inf (JSON has no NaN).
void put_number(std::string& o, double v);

template <typename F>
std::string js_array(std::size_t n, F&& value) {
  std::string o = "[";
  o.reserve(n * 8 + 2);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) o += ',';
    put_number(o, value(i));
  }
  return o + "]";
}

std::string basename_of(const std::string& path);

// RFC 4648 base64 (with padding), for images inlined as data: URLs.
std::string base64(std::string_view bytes);

// "<!DOCTYPE html>…<body>": title, uPlot's and the page's style, and the error hooks (installed
// first, so that an error anywhere later is recorded in window.cncoreErrors).
std::string head(const std::string& title, std::string_view style);

// The status element the browser test reads (data-charts, data-canvases, data-inked,
// data-errors, data-rendered); errors are shown in it.
inline constexpr std::string_view kStatusDiv = "<div id=\"cncore-status\"></div>\n";

// "<script>uPlot</script><script>helpers</script><script>DATA</script><script>PAGE</script>
// </body></html>". The helpers define window.cncore = {charts, fmt, width, chart(id, title,
// series, data, axes, scales), check()}; the page script draws, then calls
// setTimeout(cncore.check, 50) once everything is drawn.
std::string tail(const std::string& data_script, std::string_view page_script);

}  // namespace cncore::io::page
