// Feed correction by direction of motion (spec 03, seed JPH0830973B2): a block-stream stage
// between the interpreter and the motion kernel. For every feed move it computes the ratio
//   FI = (unit direction of motion) · u        (u: the configured unit direction, Z by default)
// and the coefficient C = uphill(FI) for FI ≥ 0, downhill(FI) for FI < 0, and hands the kernel
// the block with feed F·C. The correction is thus one more factor in the commanded feed, before
// the look-ahead: acc/dec and every limit of spec 01 keep holding, and the kernel reports C of
// the segment under the tool in Sample::correction.
//
// Arcs and helices: the direction changes inside the block, so an arc whose FI varies is split
// into sub-arcs of at most arc_step_deg, each with the C of the tangent at its middle. Along a
// sub-arc FI(φ) = a·cos(φ − φ0) + b with a ≤ 1, so it differs from the middle value by at most
// a·δ/2 (δ the sub-arc angle in rad): 0.044 for the default 5°. Arcs whose FI is constant
// (the plane is normal to u, e.g. G17 arcs with u = Z) are not split.
//
// Not corrected (C = 1): G0, moves without an X/Y/Z component, and moves while the correction
// is switched off in the program (M161 … M160). With `enabled = false` every block passes
// unchanged (NaN correction), so the run is exactly the uncorrected one.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "config/machine_config.hpp"
#include "core/block.hpp"

namespace cncore::feed {

// The program switch (documented in docs/gcode.md): M160 on, M161 off.
inline constexpr double kCorrectionOnM = 160;
inline constexpr double kCorrectionOffM = 161;

class DirectionCorrector {
 public:
  // Compiles the laws (they were checked when the configuration was loaded).
  // program_path: the file named in errors.
  explicit DirectionCorrector(const MachineConfig& machine, const std::string& program_path = "");
  ~DirectionCorrector();
  DirectionCorrector(const DirectionCorrector&) = delete;
  DirectionCorrector& operator=(const DirectionCorrector&) = delete;

  // Takes the next interpreted block. Then call next() until it returns false: one block out
  // for most blocks, several sub-arcs for an arc whose direction ratio varies. Memory does not
  // depend on the number of sub-arcs (they are produced one at a time).
  void put(const Block& block);
  bool next(Block& out);

  // C for a unit direction of motion d (XYZ) and programmed feed F. Throws InputError (at the
  // block's line) if a formula yields a non-finite or non-positive C there (the load-time check
  // covers a grid of FI and F; a formula can still misbehave between grid points).
  double coefficient(const Vec3& unit_direction, double feed_mm_min, const Block& where) const;
  double ratio(const Vec3& unit_direction) const;  // FI, clamped to [−1, 1]

  bool enabled() const;
  bool active() const;  // enabled and switched on at this point of the program

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncore::feed
