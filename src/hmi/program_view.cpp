#include "hmi/program_view.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <utility>

#include "core/block.hpp"
#include "interpreter/interpreter.hpp"

namespace cncore::hmi {

// Rodrigues' rotation of u (perpendicular to the unit normal n) by θ about n:
//   p(θ) = c + u·cos θ + (n × u)·sin θ + n·h·θ/Θ,   Θ the whole turn, h the rise along n.
// Θ is the counter-clockwise angle from u to the end's projection (0 → a full circle) plus one
// full turn per extra turn.
std::vector<Vec3> arc_points(const Vec3& start, const Vec3& end, const Vec3& center,
                             const Vec3& normal, std::uint32_t turns, double max_angle_rad) {
  const Vec3 u = start - center;
  const double rise = dot(normal, end - start);
  const Vec3 v = (end - rise * normal) - center;
  double theta = std::atan2(dot(normal, cross(u, v)), dot(u, v));
  if (theta <= 1e-9) theta += 2 * std::numbers::pi;
  theta += 2 * std::numbers::pi * turns;
  const auto n = static_cast<std::size_t>(
      std::clamp(std::ceil(theta / std::max(max_angle_rad, 1e-3) - 1e-9), 1.0, 4096.0));
  const Vec3 w = cross(normal, u);
  std::vector<Vec3> out;
  out.reserve(n);
  for (std::size_t i = 1; i < n; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(n);
    const double a = theta * f;
    out.push_back(center + std::cos(a) * u + std::sin(a) * w + (rise * f) * normal);
  }
  out.push_back(end);
  return out;
}

namespace {

constexpr double kArcChordRad = 5 * std::numbers::pi / 180;

std::string read_text(const std::string& path, bool& truncated) {
  std::ifstream f(path, std::ios::binary);
  std::string text;
  text.resize(ProgramView::kMaxTextBytes + 1);
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(f.gcount()));
  truncated = text.size() > ProgramView::kMaxTextBytes;
  if (truncated) text.resize(ProgramView::kMaxTextBytes);
  return text;
}

}  // namespace

ProgramView::ProgramView(const std::string& path, std::string name, const MachineConfig& machine,
                         const AxisVec& work_offset)
    : name_(std::move(name)) {
  interp::Interpreter interpreter(path, machine, interp::Options{});
  const Vec3 shift = work_offset.xyz();
  Block b;
  bool first = true;
  while (interpreter.next(b)) {
    if (!is_motion(b)) continue;
    if (b.line >= line_feed_.size()) line_feed_.resize(b.line + 1, 0.0F);
    line_feed_[b.line] = static_cast<float>(b.feed_mm_min);
    if (first) {
      add(b.start.xyz() + shift, 2, 0, b.line);
      first = false;
    }
    const std::uint8_t kind = b.kind == BlockKind::kRapid ? 0 : 1;
    if (b.kind == BlockKind::kArc) {
      for (const Vec3& p :
           arc_points(b.start.xyz(), b.end.xyz(), b.center, b.normal, b.turns, kArcChordRad)) {
        add(p + shift, kind, b.feed_mm_min, b.line);
      }
    } else {
      add(b.end.xyz() + shift, kind, b.feed_mm_min, b.line);
    }
  }
  bool text_truncated = false;
  const std::string text = read_text(path, text_truncated);
  truncated_ = truncated_ || text_truncated;
  build_json(text);
}

void ProgramView::add(const Vec3& p, std::uint8_t kind, double feed_mm_min, std::uint32_t line) {
  if (vertices_.size() >= kMaxVertices) {
    truncated_ = true;
    return;
  }
  vertices_.push_back({p, kind, static_cast<float>(feed_mm_min), line});
}

void ProgramView::build_json(const std::string& text) {
  // Numbers written by hand (3 decimals: µm) rather than through nlohmann: a few bytes per
  // number instead of 17 digits, for paths of hundreds of thousands of points.
  std::string out;
  out.reserve(64 + text.size() + vertices_.size() * 40);
  out += R"({"name":)";
  out += nlohmann::json(name_).dump();
  out += R"(,"text":)";
  out += nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  out += fmt::format(R"(,"truncated":{},"vertices":{},"xyz":[)", truncated_, vertices_.size());
  auto it = std::back_inserter(out);
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const Vertex& v = vertices_[i];
    fmt::format_to(it, "{}{:.3f},{:.3f},{:.3f}", i == 0 ? "" : ",", v.p.x, v.p.y, v.p.z);
  }
  out += R"(],"kind":[)";
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    fmt::format_to(it, "{}{}", i == 0 ? "" : ",", vertices_[i].kind);
  }
  out += R"(],"feed":[)";
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    fmt::format_to(it, "{}{:.0f}", i == 0 ? "" : ",", vertices_[i].feed_mm_min);
  }
  out += R"(],"line":[)";
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    fmt::format_to(it, "{}{}", i == 0 ? "" : ",", vertices_[i].line);
  }
  out += "]}";
  json_ = std::move(out);
}

}  // namespace cncore::hmi
