// Time-optimal lower bound for a part program on a machine: the shortest time to run the exact
// programmed path with |tangential acceleration| ≤ Amax, the speed at every point ≤ min(F, Vmax,
// per-axis limits by direction, √(R·Amax) on arcs), every corner passed at ≤ Amax·τ/(2 sin(θ/2))
// (and ≤ A_i·τ/|ΔT_i| per axis), and a stop wherever the program stops (exact stop, dwell —
// whose time is added —, waiting M-codes, the end). No real controller can be faster under
// those limits, so (kernel cycle time) / bound ≥ 1 measures what the acc/dec method wastes.
//
// Two models (Model):
// - kSimple (the first bound, `cncore-bound --model simple`): constant acceleration Amax along
//   every segment. Exact per segment: v² is linear in the path length, so a forward pass
//   (acceleration) and a backward pass (braking) over the joint speeds give the optimal joint
//   speeds, and each segment runs accelerate–cruise–decelerate in closed form. It lets the
//   tangential acceleration on an arc be Amax whatever the normal acceleration v²κ is, although
//   the checker bounds every AXIS's acceleration a_i = a_t·T_i + v²κ·N_i (and the resultant when
//   configured): on an arc at its speed limit √(R·Amax) (v²κ = Amax) an axis at 45° to the
//   tangent leaves a_t ≤ (√2 − 1)·Amax, not Amax. Lines: per-axis acceleration ignored too.
// - kCoupled (default): lines accelerate at min(Amax, A_i/|T_i|); arcs are cut into pieces of
//   ≤ 1° and on each piece the tangential acceleration at speed v is limited by
//   ā(v) = min(Amax, √(Ar² − (v²κ)²) if a resultant limit Ar is set,
//              min over axes i whose T_i, N_i keep one sign on the piece of
//              (A_i − v²κ·min|N_i|)/min|T_i|)
//   (the axes that bind accelerating have T_i·N_i > 0, those that bind braking T_i·N_i < 0).
//   Why it is still a lower bound: at every point of the piece and speed v, any feasible a_t is
//   ≤ ā(v) (each term only drops constraints or uses the piece's smallest |T_i|, |N_i|, which
//   makes it larger), and ā is non-increasing in v. So from a node where every feasible speed
//   is ≤ u0, v(s)² ≤ u0² + 2·ā(u0)·s along the piece (comparison: where v(s)² first exceeded
//   that line v ≥ u0, so d(v²)/ds = 2a_t ≤ 2ā(v) ≤ 2ā(u0)), likewise backwards from the exit
//   with the braking ā_b(u1). The passes and the per-piece time ∫ds/min(cap, forward, backward)
//   therefore bound every feasible profile from above in speed and below in time.
// Memory: about 5 numbers per segment (an arc: one per ≤ 1° piece plus its axis terms).
// Both models are continuous in time (see bench/README.md for what that leaves out: a sampled
// trajectory starts with v = Amax·τ in its first cycle, ~τ/2 ahead of the continuous ramp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"
#include "jerk_bound.hpp"
#include "limits.hpp"
#include "path_geometry.hpp"

namespace cncore::bound {

enum class Model : std::uint8_t {
  kSimple,   // constant Amax along every segment (the first bound)
  kCoupled,  // per-axis share of lines, normal acceleration's share on arcs (default)
};

struct BoundResult {
  double time_s = 0;         // motion time + dwell time
  double motion_time_s = 0;  // with a jerk limit (Limits::max_jerk_mm_s3 > 0) the jerk-aware bound
  double accel_motion_time_s = 0;  // the acceleration bound's motion time (jerk ignored)
  double dwell_s = 0;
  double length_mm = 0;      // XYZ path length
  std::size_t segments = 0;  // moving segments
  std::size_t stops = 0;     // joints where the program stops (incl. the end)
};

// One moving segment of the optimal profile (BoundBuilder::record_segments).
struct SegmentTime {
  std::uint32_t line = 0;  // source line of the block
  bool arc = false;
  double length = 0;     // mm (degrees for a rotary-only move)
  double cap_mm_s = 0;   // speed cap inside the segment
  double v_in_mm_s = 0;  // optimal speed at its start and end joint
  double v_out_mm_s = 0;
  double join_cap_mm_s = 0;  // the corner/stop cap at its end joint alone (before the passes)
  double time_s = 0;
  Vec3 start, end;  // XYZ of the block's start and end
};

// Feed blocks in program order, then finish(). With Limits::max_jerk_mm_s3 > 0 the motion time
// is the jerk-aware bound of jerk_bound.hpp over this bound's speed envelope (segment_times()
// stay the acceleration bound's).
class BoundBuilder {
 public:
  explicit BoundBuilder(const testing::Limits& limits, Model model = Model::kCoupled)
      : lim_(limits), model_(model) {}
  void add(const Block& block);
  // Also keep one SegmentTime per moving segment (finish() fills segment_times()).
  void record_segments(bool on) { record_ = on; }
  BoundResult finish();
  const std::vector<SegmentTime>& segment_times() const { return times_; }

 private:
  static constexpr std::uint32_t kNoPiece = 0xffffffffu;
  struct Seg {
    double length = 0;  // mm (XYZ), or degrees for a rotary-only move
    double cap = 0;     // speed cap inside the segment, mm/s (deg/s)
    double accel = 0;   // acceleration limit along it (an upper bound of ā(v) on arc pieces)
    double join = 0;    // speed limit at its END joint (0 = stop)
    std::uint32_t line = 0;
    bool arc = false;
    bool continues = false;          // the next Seg is the next piece of the same arc
    std::uint32_t piece = kNoPiece;  // index into pieces_ (arc pieces, kCoupled)
    Vec3 start, end;                 // XYZ (record_segments only; an arc piece: the whole arc's)
  };
  // One axis's term (A_i − v²κ·n)/t of ā(v) on an arc piece.
  struct AxisTerm {
    double a = 0, n = 0, t = 0;  // A_i, min |N_i|, min |T_i| (t = 0: unused)
  };
  struct Piece {
    double kappa = 0;
    AxisTerm acc[3], brake[3];
  };
  // ā(v) of segment s accelerating (brake = false) or braking.
  double accel_at(const Seg& s, double v, bool brake) const;
  void add_arc_pieces(const testing::PathSegment& sg, Seg s);
  // The forward and backward passes: u[0] = 0, u[k+1] the speed at the end of segs[k].
  std::vector<double> node_speeds(const std::vector<Seg>& segs) const;
  std::vector<EnvelopePiece> envelope(const std::vector<Seg>& segs,
                                      const std::vector<double>& u) const;
  // The jerk-aware motion time (jerk_bound.hpp): the envelope, its peaks capped, the passes
  // again, the valleys rounded.
  double jerk_motion_time() const;
  testing::Limits lim_;
  Model model_ = Model::kCoupled;
  std::vector<Seg> segs_;
  std::vector<Piece> pieces_;
  testing::PathSegment prev_;
  bool have_prev_ = false;
  bool prev_rotary_only_ = false;
  double dwell_s_ = 0;
  std::size_t block_index_ = 0;
  double length_mm_ = 0;
  bool record_ = false;
  std::vector<SegmentTime> times_;
};

BoundResult optimal_profile(const std::vector<Block>& blocks, const testing::Limits& limits,
                            Model model = Model::kCoupled);
double optimal_time_s(const std::vector<Block>& blocks, const testing::Limits& limits,
                      Model model = Model::kCoupled);

// Time to run `length` from speed v0 to v1 with cap vc and acceleration a (v0, v1 reachable:
// |v1² − v0²| ≤ 2·a·length): accelerate, cruise at the cap if it is reached, decelerate.
double segment_time_s(double length, double v0, double v1, double vc, double a);
// The same with acceleration a up from v0 and braking d down to v1: ∫ds / min(vc, √(v0² + 2as),
// √(v1² + 2d(L − s))) — a lower bound of the time of any profile that is ≤ v0 at the start,
// ≤ v1 at the end and within those accelerations (v0, v1 need not be reachable).
double segment_time_s(double length, double v0, double v1, double vc, double a, double d);

}  // namespace cncore::bound
