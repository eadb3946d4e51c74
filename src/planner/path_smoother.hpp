// Path smoothing within the contour tolerance, before the look-ahead (the stage between the
// direction correction and the collinear merge, planner/line_merge.hpp): runs of short G1 chords
// whose vertices lie within a tolerance of one line, circular arc or helix run as that curve.
//
// CAM output writes curves as chords: a circle of 36 000 chords with 4-decimal coordinates turns
// at every vertex, and the look-ahead, which must keep every programmed corner, runs it at the
// speed of its corners (4.8 s for an R 20 circle at F5000 that runs in 2.1 s as two G3 arcs).
// Handed arcs, the planner limits the speed by the curvature (√(R·Amax)) and the axis limits.
//
// A run is a chain of G1 blocks moving X Y Z only, with feeds within 0.1 % (the curve runs at
// the lowest), the same G64 tolerances and override/correction flags, joined at vertices that
// may be rounded (G64: a G61, G61.1 or G9 vertex ends the run, kept exact), and whose joints are
// not real corners: a joint turning by more than the corner angle between two chords both longer
// than the tolerance stays a corner. Turns between shorter chords are the noise of rounded
// coordinates at the tolerance's scale; whether they lie on a curve is the fit's to decide.
// From the front of a run the stage takes the longest prefix that one curve fits
// (geometry/curve_fit.hpp: every point of the curve within the tolerance of the chords and every
// point of the chords within the tolerance of the curve, curve ends on programmed vertices) by
// doubling its length, then bisecting; a chord no curve fits goes out as programmed. After a
// curve, the arc that leaves along its end tangent is taken when it fits at least as many
// chords as any other curve (an arc spline without kinks). The joints (keeps_joints()): a curve
// never makes the joint before it turn more than the chords did there (or than free_turn_rad):
// an arc through two chords of a polygon turns away from its neighbours by half its own turn,
// and the look-ahead would pass those joints slower than the chords' corners. It ends along the
// data's own direction (the chord over ±50 tolerances, where the run goes on that far in 4
// chords or more, within the free turn or half the data's turn over that span), so that it does
// not reach past an inflection; else its end turns against the next chord no more than the
// chords did, the free turn, or its own end differs from its last chord.
//
// The tolerance of a block is G64 Q (Block::smooth_tolerance_mm; 0: off), else the machine's
// [motion] smooth_tolerance_mm (0 by default: off), and never more than its contour tolerance
// (G64 P, else [motion] contour_tolerance_mm), so the executed path stays within the tolerance
// the program asked for (less the collinear merge's tolerance, which acts after it). Off in stop
// mode.
//
// Memory: a run holds at most kMaxChords chords (allocated once); a full run hands out its
// first curve before it takes the next chord. Cost per chord: O(log kMaxChords) fits of O(run)
// each, at most, in the planning stage (never in the motion cycle).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"
#include "geometry/curve_fit.hpp"

namespace cncore::planner {

using geometry::CurveFit;
using geometry::CurveFitLimits;
using geometry::fit_curve;
using geometry::fit_tangent_curve;

struct SmoothingSettings {
  double tolerance_mm = 0;  // [motion] smooth_tolerance_mm; ≤ 0: only G64 Q turns it on
  double corner_deg = 30;   // [motion] smooth_corner_deg
  double contour_tolerance_mm = 0.01;  // [motion] contour_tolerance_mm (blocks without G64 P)
  double reserve_mm = 0;  // taken off every tolerance: what the stages after it may deviate
  // A joint turning by at most this needs no slowing (LineMerger::max_turn_rad): a curve may
  // turn its end joints up to it even where the chords turned less.
  double free_turn_rad = 0;
};

class PathSmoother {
 public:
  static constexpr std::size_t kMaxChords = 1024;

  explicit PathSmoother(const SmoothingSettings& settings);

  // The next block in program order. Then call next() until it returns false.
  void put(const Block& block);
  // The program ends (or stops on an error): the run held goes out.
  void finish();
  // The blocks ready, in program order.
  bool next(Block& out);

  // G1 chords taken into runs, and the blocks that went out for them (the smoothing ratio is
  // chords_in / blocks_out).
  std::uint64_t chords_in() const { return chords_in_; }
  std::uint64_t blocks_out() const { return blocks_out_; }
  // Of blocks_out, those that replace two or more chords.
  std::uint64_t curves_out() const { return curves_out_; }

  // The smoothing tolerance of a block (0: not smoothed).
  double tolerance_of(const Block& b) const;

 private:
  bool joins(const Block& b, double tol) const;
  bool keeps_joints(std::size_t chords, const CurveFit& fit) const;
  void set_exit(const Block& b, const Vec3& dir);
  void emit_front();  // the longest fitting prefix of the run (at least one chord)
  // The most chords one curve fits from the run's front (1: none), leaving along in_dir_
  // (tangent) or by any curve that keeps the joints.
  std::size_t longest_fit(bool tangent, CurveFit& best_fit) const;
  Block make_piece(std::size_t chords, const CurveFit* fit) const;
  void emit(const Block& b);

  SmoothingSettings settings_;
  double cos_corner_;
  std::vector<Block> run_;    // the chords held (capacity kMaxChords)
  std::vector<Vec3> points_;  // their vertices: run_.size() + 1 once a run is open
  double run_tol_ = 0;
  double feed_lo_mm_min_ = 0, feed_hi_mm_min_ = 0;
  double cos_free_turn_;
  // Unit directions into the run's first vertex and out of its last (zero: unknown, not a
  // line), and of the last block handed out at its end point.
  Vec3 in_dir_, out_dir_, exit_dir_;
  Vec3 chord_in_dir_;       // the programmed chord into the run's first vertex
  bool continued_ = false;  // the run's front follows a curve of the run (in_dir_ its tangent)
  AxisVec exit_pos_;
  std::vector<Block> out_;  // ready, from out_head_ on
  std::size_t out_head_ = 0;
  std::uint64_t chords_in_ = 0, blocks_out_ = 0, curves_out_ = 0;
};

}  // namespace cncore::planner
