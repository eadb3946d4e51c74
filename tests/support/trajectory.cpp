#include "trajectory.hpp"

#include <fast_float/fast_float.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string_view>

namespace cncore::testing {

void Trajectory::reserve(std::size_t n) {
  t_s.reserve(n);
  line.reserve(n);
  pos.reserve(n);
  feed_mm_min.reserve(n);
  override_pct.reserve(n);
  correction.reserve(n);
}

void Trajectory::add(double t, std::uint32_t line_no, const AxisVec& p, double feed,
                     double override, double corr) {
  if (t_s.size() == 1) period_s = t - t_s[0];
  t_s.push_back(t);
  line.push_back(line_no);
  pos.push_back(p);
  feed_mm_min.push_back(feed);
  override_pct.push_back(std::isnan(override) ? 100.0 : override);
  correction.push_back(std::isnan(corr) ? 1.0 : corr);
}

namespace {

enum Col : int { kT = 0, kLine, kAx0, kFeed = kAx0 + 6, kOverride, kCorrection, kNumCols };

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '"'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r' || s.back() == '"'))
    s.remove_suffix(1);
  return s;
}

int column_of(std::string_view name) {
  static constexpr std::array<std::string_view, kNumCols> kNames = {
      "t", "line", "x", "y", "z", "a", "b", "c", "feed", "override", "correction"};
  for (int i = 0; i < kNumCols; ++i)
    if (name == kNames[static_cast<std::size_t>(i)]) return i;
  return -1;
}

}  // namespace

Trajectory load_trajectory_csv(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw std::runtime_error(path + ": cannot open trajectory file");
  std::string data;
  {
    std::array<char, 1 << 16> buf{};
    std::size_t n = 0;
    while ((n = std::fread(buf.data(), 1, buf.size(), f.get())) > 0) data.append(buf.data(), n);
  }
  const std::string_view all(data);
  std::size_t at = 0;
  std::size_t line_no = 0;
  auto next_line = [&](std::string_view& out) {
    if (at >= all.size()) return false;
    std::size_t e = all.find('\n', at);
    if (e == std::string_view::npos) e = all.size();
    out = all.substr(at, e - at);
    at = e + 1;
    ++line_no;
    return true;
  };
  auto fail = [&](const std::string& msg) {
    throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + msg);
  };

  std::string_view header;
  if (!next_line(header)) fail("empty trajectory file");
  std::vector<int> map;  // file column → our column (−1: ignored)
  std::array<bool, kNumCols> present{};
  {
    std::size_t p = 0;
    while (p <= header.size()) {
      std::size_t e = header.find(',', p);
      if (e == std::string_view::npos) e = header.size();
      const int c = column_of(trim(header.substr(p, e - p)));
      map.push_back(c);
      if (c >= 0) present[static_cast<std::size_t>(c)] = true;
      p = e + 1;
    }
  }
  if (!present[kT]) fail("no column 't'");
  if (!present[kLine]) fail("no column 'line'");
  bool any_axis = false;
  for (int i = 0; i < 6; ++i) any_axis = any_axis || present[static_cast<std::size_t>(kAx0 + i)];
  if (!any_axis) fail("no axis column (x y z a b c)");

  Trajectory tr;
  tr.reserve(all.size() / 40);
  std::string_view row;
  std::array<double, kNumCols> v{};
  int max_decimals = 0;
  while (next_line(row)) {
    if (trim(row).empty()) continue;
    v = {};
    v[kOverride] = 100;
    v[kCorrection] = 1;
    const char* p = row.data();
    const char* end = row.data() + row.size();
    for (std::size_t c = 0; c < map.size(); ++c) {
      while (p < end && (*p == ' ' || *p == '\t')) ++p;
      const char* field_end = p;
      while (field_end < end && *field_end != ',') ++field_end;
      if (map[c] >= 0) {
        const int col = map[c];
        if (col >= kAx0 && col < kAx0 + 6) {
          // Count the decimals of axis values: the resolution of the file.
          const char* dot = p;
          while (dot < field_end && *dot != '.' && *dot != 'e' && *dot != 'E') ++dot;
          if (dot < field_end && *dot == '.') {
            const char* e = dot + 1;
            while (e < field_end && *e >= '0' && *e <= '9') ++e;
            const bool exponent = e < field_end && (*e == 'e' || *e == 'E');
            if (!exponent)
              max_decimals = std::max(max_decimals, static_cast<int>(e - dot - 1));
            else
              max_decimals = 17;
          } else if (dot < field_end) {
            max_decimals = 17;  // exponent form: treat as exact
          }
        }
        double x = 0;
        const char* q = p;
        if (q < field_end && *q == '+') ++q;
        auto res = fast_float::from_chars(q, field_end, x);
        const bool empty = (q == field_end) || (*q == '\r');
        if (empty) {
          x = std::nan("");  // an empty optional value (e.g. load when inactive)
        } else if (res.ec != std::errc()) {
          fail("bad number in column " + std::to_string(c + 1));
        }
        v[static_cast<std::size_t>(map[c])] = x;
      }
      const bool had_comma = field_end < end;
      p = had_comma ? field_end + 1 : end;
      if (!had_comma && c + 1 < map.size()) {
        // Short row: only acceptable if the remaining columns are ignored ones.
        for (std::size_t r = c + 1; r < map.size(); ++r)
          if (map[r] >= 0) fail("row has fewer columns than the header");
        break;
      }
    }
    AxisVec pos;
    for (std::size_t i = 0; i < 6; ++i) {
      const double x = v[static_cast<std::size_t>(kAx0) + i];
      pos[i] = std::isnan(x) ? 0.0 : x;
    }
    if (std::isnan(v[kT])) fail("empty time");
    tr.add(v[kT], static_cast<std::uint32_t>(std::isnan(v[kLine]) ? 0 : v[kLine]), pos, v[kFeed],
           v[kOverride], v[kCorrection]);
  }
  tr.position_resolution_mm = max_decimals >= 15 ? 0.0 : 0.5 * std::pow(10.0, -max_decimals);
  if (tr.size() >= 2) {
    // Period from the mean spacing of the time column, rounded to the ns (CSV decimals).
    const double mean = (tr.t_s.back() - tr.t_s.front()) / static_cast<double>(tr.size() - 1);
    tr.period_s = std::round(mean * 1e9) / 1e9;
  }
  return tr;
}

}  // namespace cncore::testing
