// Part-program generators for tests and benchmarks: G-code text (RS274/NGC, mm, G90, G17) for
// the typical shapes that stress a look-ahead planner. Every program starts with a rapid to its
// first point, stays inside the built-in machine's travel (X ±300, Y ±200, Z −200…100) and ends
// with M30. Deterministic: the same arguments (and seed) give the same text.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <ostream>
#include <string>

#include "core/block.hpp"

namespace cncore::testing::gen {

// N strokes of length L along X, stepping `pitch_mm` in Y between strokes (each step is a
// short stroke of its own, so every joint is a 90° corner).
std::string zigzag(int strokes, double length_mm, double pitch_mm = 1.0,
                   double feed_mm_min = 10000);

// A full circle of radius R approximated by N chords (G1), starting at (R, 0).
std::string circle_chords(int chords, double radius_mm, double feed_mm_min = 10000);

// A 3-D raster of z = f(x, y) over [−w/2, w/2] × [−h/2, h/2]: rows along X every `stepover_mm`
// in Y, points every `spacing_mm`, alternating direction. Default surface: a smooth bump
// (0–5 mm deep waves).
std::string raster_3d(double width_mm, double height_mm, double stepover_mm, double spacing_mm,
                      double feed_mm_min = 10000,
                      const std::function<double(double, double)>& surface = {});

// A seeded random path of `segments` short G1 segments (lengths in [min_len, max_len], turns of
// up to ±max_turn_deg), kept inside ±100 × ±100, Z in [−5, 0]. With `refine` = k every segment is
// cut into k equal pieces: the same geometry in k× more blocks.
std::string random_path(std::uint64_t seed, int segments, double min_len_mm = 0.2,
                        double max_len_mm = 2.0, double max_turn_deg = 90, int refine = 1,
                        double feed_mm_min = 10000);

// A CAM-like finishing program of about `lines` lines (3-D raster of short G1 segments with
// retracts between passes, feed words, a few arcs), written straight to `out` so that a million
// lines do not have to be held in memory.
void cam_like(std::ostream& out, std::size_t lines, std::uint64_t seed = 1);

// Writes interpreted Blocks back as G-code (machine coordinates, mm, G90, no offsets), every
// motion block cut into `refine` equal pieces (lines: equal lengths; arcs: equal angles; multi-turn
// arcs stay whole). Exact stops become G9, dwells G4, waiting M-codes G4 P0; feeds, G61/G64 kept.
// The result runs the same path as the original, with `refine`× as many blocks (spec 01 P7).
class GcodeWriter {
 public:
  GcodeWriter(std::ostream& out, int refine);
  void add(const Block& block);
  void finish();  // writes M30

 private:
  void motion_word(const char* g, const AxisVec& end);
  std::ostream& out_;
  int refine_;
  double feed_ = -1;
  int plane_ = 17;
  PathMode mode_ = PathMode::kBlend;
  double tolerance_ = -1;
  std::array<bool, kMaxAxes> rotary_used_{};  // once written, a rotary axis is always written
};

}  // namespace cncore::testing::gen
