// What the operator page shows of a loaded program: its text and its path as a polyline (rapids
// and cuts, arcs as chords), with the programmed feed per line. Interpreted once when the program
// is loaded; bounded in size whatever the program's length (kMaxVertices, kMaxTextBytes).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"

namespace cncore::hmi {

class ProgramView {
 public:
  static constexpr std::size_t kMaxVertices = 400000;
  static constexpr std::size_t kMaxTextBytes = std::size_t{8} << 20;

  ProgramView() = default;
  // Interprets the program at `path` (which the controller has accepted) in the default modal
  // state; `work_offset` is added to every point (the controller's active offset, which the
  // program's coordinates are relative to). Throws InputError on an unreadable program.
  ProgramView(const std::string& path, std::string name, const MachineConfig& machine,
              const AxisVec& work_offset);

  const std::string& name() const { return name_; }
  // The programmed feed of the block at a source line (0: none or a rapid).
  double feed_at_line(std::uint32_t line) const {
    return line < line_feed_.size() ? line_feed_[line] : 0.0;
  }
  // {"name","text","truncated","vertices":N,"xyz":[…],"kind":[…],"feed":[…],"line":[…]}: vertex
  // i > 0 ends the segment from vertex i−1 whose kind (0 rapid, 1 feed move), programmed feed
  // (mm/min) and source line it carries; a vertex of kind 2 starts a new run (no segment to it).
  const std::string& json() const { return json_; }

  struct Vertex {
    Vec3 p;
    std::uint8_t kind = 0;
    float feed_mm_min = 0;
    std::uint32_t line = 0;
  };
  const std::vector<Vertex>& vertices() const { return vertices_; }
  bool truncated() const { return truncated_; }

 private:
  void add(const Vec3& p, std::uint8_t kind, double feed_mm_min, std::uint32_t line);
  void build_json(const std::string& text);

  std::string name_;
  std::vector<Vertex> vertices_;
  std::vector<float> line_feed_;
  bool truncated_ = false;
  std::string json_ = R"({"name":"","text":"","truncated":false,"vertices":0})";
};

// Points along an arc block from its start (excluded) to its end (included), chords no longer
// than max_angle_rad of turn: the motion turns counter-clockwise about `normal` around `center`
// and rises along it linearly (a helix).
std::vector<Vec3> arc_points(const Vec3& start, const Vec3& end, const Vec3& center,
                             const Vec3& normal, std::uint32_t turns, double max_angle_rad);

}  // namespace cncore::hmi
