// The lathe cycles G70 (finishing), G71 (roughing along Z) and G72 (facing, roughing along X)
// of LinuxCNC, as pure geometry: a profile of lines and arcs in the ZX plane in, the moves of
// the cycle out. The interpreter (lathe_cycles.cpp) reads the profile from the subroutine
// named by Q and turns the moves into blocks.
//
// A point is a complex number z + i·x (Z real, X imaginary, X a radius), so that turning,
// mirroring and offsetting are one multiplication. The cycles work on a normalised profile:
// it is mirrored (and for G72 turned by 90°) until it runs towards −Z and −X, and each output
// move is mapped back (Orientation). The roughing then cuts passes at X = x0 − n·I along −Z
// from the start point to the profile offset by the allowance D, retracting by R at 45°, and
// cuts each pocket (a stretch where the profile climbs back in X) when the contour reaches it.
#pragma once

#include <complex>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace cncore::interp::lathe {

using Pt = std::complex<double>;  // z + i·x

// Every failure of a cycle's geometry (a profile that is not monotonic, a corner that cannot
// be finished, a pass that makes no progress); the interpreter reports it at the cycle's line.
struct ProfileError {
  std::string message;
};

enum class SegKind : std::uint8_t {
  kLine,
  kArc,
  kFillet,   // A word: a rounded corner of radius `finish` at `start`, made by finish_corners()
  kChamfer,  // C word: a chamfer of size `finish`
};

struct Seg {
  SegKind kind = SegKind::kLine;
  Pt start, end;
  Pt centre;  // arcs and fillets
  bool ccw = false;
  double finish = 0;

  bool round() const { return kind == SegKind::kArc || kind == SegKind::kFillet; }
};

using Profile = std::vector<Seg>;

Seg line_seg(Pt start, Pt end);
Seg arc_seg(bool ccw, Pt start, Pt centre, Pt end);

// The moves of a cycle, in program coordinates (the interpreter's units, X a radius).
class MoveSink {
 public:
  virtual ~MoveSink() = default;
  virtual void rapid(Pt end) = 0;
  virtual void feed(Pt end) = 0;
  virtual void arc(bool ccw, Pt centre, Pt end) = 0;
};

struct RoughingParams {
  int variant = 0;       // G71 / G71.1 / G71.2: 0 with pockets, 1 without, 2 only the pockets
  bool facing = false;   // G72: passes along X
  Pt start;              // the cycle's start point (X Z words)
  Pt shift;              // W + i·U: the profile moved by this
  double allowance = 0;  // D: stock left on the profile
  double depth = 1;      // I: depth of each pass (> 0)
  double retract = 0.5;  // R: the 45° retraction after each pass
};

struct FinishingParams {
  Pt start;
  double first_allowance = 0;  // D: the distance of the first pass
  double last_allowance = 0;   // E: the distance of the last pass
  int passes = 1;              // P
};

// The profile's first segment runs from the position before the cycle to the profile's start;
// both functions replace its start with the cycle's start point. They throw ProfileError.
void rough(Profile profile, const RoughingParams& p, MoveSink& out);
void finish(Profile profile, const FinishingParams& p, MoveSink& out);

// Segment geometry (lathe_profile.cpp), used by the cycles (lathe_cycles_geometry.cpp).
namespace seg {
inline constexpr double kTol = 1e-6;
using Hits = std::deque<double>;
void offset(Seg& s, double d);  // to the side of +i·(start − end) for lines
double size(const Seg& s);      // length, or the smaller of chord and radius
bool monotonic(const Seg& s);   // does not climb back in Z (−Z is forward)
void flip_x(Seg& s);            // x → −x
void flip_z(Seg& s);            // z → −z
void turn(Seg& s);              // by −90°: p → −i·p
void shift(Seg& s, Pt d);
void hits_at_x(const Seg& s, double x, Hits& out);  // Z where the segment crosses X = x
// The joint of `prev` and `next` moved to where the two (offset) curves intersect.
void join(Seg& prev, Seg& next);
Pt finish_corner(Seg& corner, Seg& prev, Seg& next);  // the corner's centre
void draw(const Seg& s, MoveSink& out);
// Following the profile from `at`. dive: down to X = x along a segment that descends; true
// when the segment climbs instead. climb: along a segment that climbs; true when it descends
// (a pocket begins there). climb_only: the climbing part of a segment from the height of `at`.
bool dive(const Seg& s, Pt& at, double x, MoveSink& out, bool rapid);
bool climb(const Seg& s, Pt& at, MoveSink& out);
void climb_only(const Seg& s, Pt& at, MoveSink& out);
}  // namespace seg

}  // namespace cncore::interp::lathe
