#include "feedcontrol/load_source.hpp"

#include <fast_float/fast_float.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace cncore::feed {

namespace {

// Linear interpolation in sorted x (non-decreasing), held outside; at a step (equal x) the
// value after the step wins. O(log n), no allocation.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (x.empty()) return 0;
  if (!(at >= x.front())) return y.front();  // also NaN
  if (at >= x.back()) return y.back();
  // First x > at; x.front() <= at, so hi >= 1 and x[lo] <= at < x[hi] (span > 0).
  const auto hi = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin());
  const std::size_t lo = hi - 1;
  const double span = x[hi] - x[lo];
  const double w = (at - x[lo]) / span;
  return y[lo] + w * (y[hi] - y[lo]);
}

std::string_view trim(std::string_view s, std::size_t& lead) {
  lead = 0;
  while (lead < s.size() && (s[lead] == ' ' || s[lead] == '\t')) ++lead;
  s.remove_prefix(lead);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

struct Field {
  std::string_view text;
  std::uint32_t col;  // 1-based column of the field's first non-blank character
};

// Splits a line at commas; columns are 1-based.
std::vector<Field> split(std::string_view line) {
  std::vector<Field> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? line.size() : comma;
    std::size_t lead = 0;
    const std::string_view raw = line.substr(start, end - start);
    const std::string_view t = trim(raw, lead);
    fields.push_back({t, static_cast<std::uint32_t>(start + lead + 1)});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

double parse_number(const Field& f, const std::string& source, std::uint32_t line,
                    const char* what) {
  if (f.text.empty())
    throw InputError(source, line, f.col, std::string("empty ") + what + " field");
  double v = 0;
  const char* first = f.text.data();
  const char* last = first + f.text.size();
  const auto r = fast_float::from_chars(first, last, v);
  if (r.ec != std::errc() || r.ptr != last) {
    throw InputError(source, line, f.col,
                     std::string(what) + " is not a number: '" + std::string(f.text) + "'");
  }
  if (!std::isfinite(v)) {
    throw InputError(source, line, f.col, std::string(what) + " must be finite");
  }
  return v;
}

}  // namespace

RecordedLoad RecordedLoad::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open load file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, 0, "cannot read load file");
  return parse(text.str(), path);
}

RecordedLoad RecordedLoad::parse(std::string_view text, const std::string& source_name) {
  RecordedLoad rec;
  bool have_header = false;
  std::uint32_t line_no = 0;
  std::uint32_t header_line = 0;
  const char* abscissa = "time";
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    std::size_t lead = 0;
    const std::string_view content = trim(line, lead);
    if (content.empty() || content.front() == '#') {
      if (nl == std::string_view::npos) break;
      continue;
    }
    const std::vector<Field> fields = split(line);
    if (!have_header) {
      if (fields.size() != 2) {
        throw InputError(source_name, line_no, 1,
                         "header must be 't_s,load_pct' or 's_mm,load_pct'");
      }
      if (fields[0].text == "t_s") {
        rec.axis_ = Axis::kTime;
        abscissa = "time";
      } else if (fields[0].text == "s_mm") {
        rec.axis_ = Axis::kDistance;
        abscissa = "distance";
      } else {
        throw InputError(source_name, line_no, fields[0].col,
                         "first column must be 't_s' (time) or 's_mm' (path distance), not '" +
                             std::string(fields[0].text) + "'");
      }
      if (fields[1].text != "load_pct") {
        throw InputError(
            source_name, line_no, fields[1].col,
            "second column must be 'load_pct', not '" + std::string(fields[1].text) + "'");
      }
      have_header = true;
      header_line = line_no;
    } else {
      if (fields.size() < 2) {
        throw InputError(source_name, line_no, static_cast<std::uint32_t>(line.size() + 1),
                         "expected 2 fields (" + std::string(abscissa) + ", load), found 1");
      }
      if (fields.size() > 2) {
        throw InputError(source_name, line_no, fields[2].col,
                         "expected 2 fields, found " + std::to_string(fields.size()));
      }
      const double x = parse_number(fields[0], source_name, line_no, abscissa);
      const double load = parse_number(fields[1], source_name, line_no, "load");
      if (load < 0)
        throw InputError(source_name, line_no, fields[1].col, "load must not be negative");
      if (!rec.x_.empty() && x < rec.x_.back()) {
        throw InputError(source_name, line_no, fields[0].col,
                         std::string(abscissa) + " goes backwards (" + std::string(fields[0].text) +
                             " after " + std::to_string(rec.x_.back()) + ")");
      }
      rec.x_.push_back(x);
      rec.load_.push_back(load);
    }
    if (nl == std::string_view::npos) break;
  }
  if (!have_header) throw InputError(source_name, line_no, 1, "empty load file: no header");
  if (rec.x_.empty()) throw InputError(source_name, header_line, 1, "load file has no data rows");
  return rec;
}

double RecordedLoad::at(double x) const noexcept {
  return interpolate(x_, load_, x);
}

double RecordedLoad::load_pct(double t_s, double path_s_mm, double /*feed_mm_min*/) noexcept {
  return at(axis_ == Axis::kTime ? t_s : path_s_mm);
}

double DepthProfile::at(double path_s_mm) const noexcept {
  return interpolate(s_mm, depth_mm, path_s_mm);
}

std::optional<SettingsProblem> DepthProfile::find_problem() const {
  const char* key = "adaptive.plant.depth";
  if (s_mm.empty()) return SettingsProblem{key, "needs at least one (s_mm, depth_mm) point"};
  if (s_mm.size() != depth_mm.size()) {
    return SettingsProblem{key, "s_mm and depth_mm differ in length"};
  }
  for (std::size_t i = 0; i < s_mm.size(); ++i) {
    const std::string at = "point " + std::to_string(i + 1) + ": ";
    if (!std::isfinite(s_mm[i]) || !std::isfinite(depth_mm[i])) {
      return SettingsProblem{key, at + "values must be finite"};
    }
    if (depth_mm[i] < 0) return SettingsProblem{key, at + "depth must not be negative"};
    if (i > 0 && s_mm[i] < s_mm[i - 1]) {
      return SettingsProblem{key, at + "path distance goes backwards"};
    }
  }
  return std::nullopt;
}

std::optional<SettingsProblem> PlantSettings::find_problem() const {
  if (!std::isfinite(base_pct) || base_pct < 0) {
    return SettingsProblem{"adaptive.plant.base_pct", "must be a finite number ≥ 0"};
  }
  if (!std::isfinite(k_pct_per_mm2_min) || k_pct_per_mm2_min < 0) {
    return SettingsProblem{"adaptive.plant.k_pct_per_mm2_min", "must be a finite number ≥ 0"};
  }
  if (!std::isfinite(time_constant_s) || time_constant_s < 0) {
    return SettingsProblem{"adaptive.plant.time_constant_s", "must be a finite number ≥ 0"};
  }
  if (!std::isfinite(noise_pct) || noise_pct < 0) {
    return SettingsProblem{"adaptive.plant.noise_pct", "must be a finite number ≥ 0"};
  }
  return depth.find_problem();
}

void PlantSettings::validate(const std::string& source) const {
  if (auto p = find_problem()) throw InputError(source, 0, 0, p->key + ": " + p->message);
}

PlantLoad::PlantLoad(PlantSettings settings)
    : settings_(std::move(settings)),
      state_pct_(settings_.base_pct),
      rng_(settings_.seed),
      noise_(0.0, settings_.noise_pct > 0 ? settings_.noise_pct : 1.0) {}

double PlantLoad::load_pct(double t_s, double path_s_mm, double feed_mm_min) noexcept {
  const double u = settings_.base_pct +
                   settings_.k_pct_per_mm2_min * std::fabs(feed_mm_min) * depth_mm(path_s_mm);
  const double dt = started_ ? std::max(0.0, t_s - last_t_s_) : 0.0;
  started_ = true;
  last_t_s_ = t_s;
  // Exact step of τ·dl/dt = u − l over Δt (holds for any Δt, unlike explicit Euler).
  if (settings_.time_constant_s <= 0) {
    state_pct_ = u;
  } else if (dt > 0) {
    state_pct_ += (u - state_pct_) * (1.0 - std::exp(-dt / settings_.time_constant_s));
  }
  const double noise = settings_.noise_pct > 0 ? noise_(rng_) : 0.0;
  return std::max(0.0, state_pct_ + noise);
}

}  // namespace cncore::feed
