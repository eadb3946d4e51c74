// G70 / G71 / G72 on a normalised profile (lathe_profile.hpp): corner finishing, the offset
// profile, and the roughing passes with their pockets. The decisions follow LinuxCNC's
// (interp_g7x), whose canonical output the interpreter tests compare move by move.
#include <algorithm>
#include <cmath>

#include "interpreter/lathe_profile.hpp"

namespace cncore::interp::lathe {

namespace {
using seg::kTol;
constexpr Pt kI{0, 1};
// Bounds on the work of one cycle, so that no profile can make it run forever.
constexpr int kMaxOffsetSteps = 100000;
constexpr long kMaxPocketSteps = 10000000;
constexpr int kMaxPockets = 10000;

// How the normalised profile was obtained from the programmed one: bit 0 z mirrored, bit 1 x
// mirrored, bit 2 turned by −90° (G72, or a G70 profile along X). Moves are mapped back.
class Oriented final : public MoveSink {
 public:
  Oriented(MoveSink& out, int state) : out_(out), state_(state) {}
  void rapid(Pt end) override { out_.rapid(back(end)); }
  void feed(Pt end) override { out_.feed(back(end)); }
  void arc(bool ccw, Pt centre, Pt end) override {
    const bool mirrored = ((state_ & 1) != 0) != ((state_ & 2) != 0);
    out_.arc(mirrored ? !ccw : ccw, back(centre), back(end));
  }

 private:
  Pt back(Pt p) const {
    if ((state_ & 1) != 0) p = -std::conj(p);
    if ((state_ & 2) != 0) p = std::conj(p);
    if ((state_ & 4) != 0) p = kI * p;
    return p;
  }
  MoveSink& out_;
  int state_;
};

struct Shape {
  Profile segs;
  int state = 0;

  void turn() {
    for (Seg& s : segs) seg::turn(s);
    state ^= 4;
  }
  // Mirror until the profile runs towards −X and −Z (from its first end to its last).
  void normalise() {
    const Pt d = segs.front().end - segs.back().end;
    if (d.imag() > 0) {
      for (Seg& s : segs) seg::flip_x(s);
      state ^= 2;
    }
    if (d.real() < 0) {
      for (Seg& s : segs) seg::flip_z(s);
      state ^= 1;
    }
  }
  void check_monotonic() {
    Seg& first = segs.front();
    if ((first.end - first.start).real() > 0) first.start.real(first.end.real());
    for (const Seg& s : segs) {
      if (!seg::monotonic(s)) throw ProfileError{"the profile is not monotonic"};
    }
  }
  void finish_corners();
  void add_distance(double distance);
  void clean_joints(double step);
};

// A and C words: each corner segment takes its ends from its neighbours.
void Shape::finish_corners() {
  for (std::size_t h = 1; h + 1 < segs.size(); ++h) {
    Seg& c = segs[h];
    if (c.kind == SegKind::kFillet) {
      c.centre = seg::finish_corner(c, segs[h - 1], segs[h + 1]);
      c.ccw = (c.start - c.centre).imag() > 0 || (c.end - c.centre).imag() > 0;
      c.finish = 0;
    } else if (c.kind == SegKind::kChamfer) {
      seg::finish_corner(c, segs[h - 1], segs[h + 1]);
    }
  }
  std::erase_if(segs, [](const Seg& s) { return seg::size(s) < 1e-3; });
  // The approach and at least one segment of the part.
  if (segs.size() < 2) throw ProfileError{"the profile has no segment longer than 0.001"};
}

// After one offset step: arcs round the outside corners that opened, short and reversed
// segments go, and the others meet again.
void Shape::clean_joints(double step) {
  for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
    if ((segs[i].end - segs[i + 1].start).real() <= 1e-2) continue;
    Seg s = segs[i], e = segs[i + 1];
    seg::offset(s, -step);
    seg::offset(e, -step);
    const Pt centre = (s.end + e.start) / 2.0;
    segs.insert(segs.begin() + static_cast<std::ptrdiff_t>(i) + 1,
                arc_seg(step > 0, segs[i].end, centre, segs[i + 1].start));
    ++i;
  }
  for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
    if (!seg::monotonic(segs[i])) {
      const bool drop_this = i == 0 || seg::size(segs[i]) < seg::size(segs[i - 1]);
      segs.erase(segs.begin() + static_cast<std::ptrdiff_t>(drop_this ? i : i - 1));
      i = 0;
      if (i + 1 >= segs.size()) break;
    }
    if (seg::size(segs[i]) < 1e-3) {
      segs.erase(segs.begin() + static_cast<std::ptrdiff_t>(i));
      i = 0;  // the next step looks at the second segment, as the loop continues
    } else {
      seg::join(segs[i], segs[i + 1]);
    }
  }
}

// The profile (without its first, approaching segment) offset by `distance` away from the
// start point, in steps of at most half the shortest segment, so that no segment inverts.
void Shape::add_distance(double distance) {
  const Pt v1 = segs.front().end - segs.front().start;
  const Pt v2 = segs.back().start - segs.front().start;
  if ((v1 / v2).imag() < 0) distance = -distance;
  const Seg approach = segs.front();
  segs.erase(segs.begin());
  double done = 0;
  for (int steps = 0; done != distance; ++steps) {
    if (segs.empty()) throw ProfileError{"the profile vanished when offset"};
    if (steps >= kMaxOffsetSteps) throw ProfileError{"the offset profile does not converge"};
    double step = 1e9;
    for (const Seg& s : segs) step = std::min(step, seg::size(s) / 2);
    step = std::min(step, std::fabs(distance - done));
    if (distance < 0) step = -step;
    for (Seg& s : segs) seg::offset(s, step);
    std::erase_if(segs, [](const Seg& s) { return seg::size(s) < 1e-3; });
    if (segs.empty()) throw ProfileError{"the profile vanished when offset"};
    clean_joints(step);
    done += step;
  }
  for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
    segs[i].end = segs[i + 1].start = (segs[i].end + segs[i + 1].start) / 2.0;
  }
  Seg first = approach;
  first.end = segs.front().start;
  segs.insert(segs.begin(), first);
}

class Roughing {
 public:
  Roughing(Profile& segs, MoveSink& out, double depth, double retract)
      : segs_(segs), out_(out), delta_(depth), escape_(retract * Pt{1, 1}) {}
  void pocket(int variant, Pt at, std::size_t p);
  std::deque<Pt> starts;  // where each pocket being cut began

 private:
  bool cut_pass(Pt& at, std::size_t& p, double& x);
  void spend() {
    if (++steps_ > kMaxPocketSteps) throw ProfileError{"the roughing makes no progress"};
  }
  int pockets_ = 0;  // pocket() calls so far: bounds its recursion
  Profile& segs_;
  MoveSink& out_;
  double delta_;
  Pt escape_;
  long steps_ = 0;
};

// One pass at X = x from `at` along −Z to the profile, then out by the 45° retraction, back
// above the start of the pass, and down again. False: the pass was not cut (the next segment
// is tried).
bool Roughing::cut_pass(Pt& at, std::size_t& p, double& x) {
  for (std::size_t ip = p; ip < segs_.size(); ++ip) {
    seg::Hits hits;
    seg::hits_at_x(segs_[ip], at.imag(), hits);
    if (hits.empty()) continue;
    const double dest_z = ip != p ? hits.front() : hits.back();  // the diving arc: its far side
    const double distance = std::fabs(dest_z - at.real());
    if (dest_z - kTol > at.real()) continue;
    if (distance < kTol) {
      if (p == ip) continue;  // the diving segment at the start point
      if (std::abs(at - segs_[ip].start) < kTol) {
        p = ip;  // another segment starts here: follow it
        return true;
      }
      x -= delta_;  // a zero-length pass
      return true;
    }
    Pt to = at;
    to.real(dest_z);
    out_.feed(to);
    const double scale = std::min(1.0, distance / 2 / escape_.real());
    out_.rapid(to + scale * escape_);
    out_.rapid(at - std::conj(scale * escape_));
    if (p == 0) {
      out_.rapid(at);
    } else {
      out_.feed(at);
    }
    x -= delta_;
    return true;
  }
  return false;
}

// Size: LinuxCNC's pocket loop in one piece; its state (the segment, the pass height, the
// position) is shared by every branch.
void Roughing::pocket(int variant, Pt at, std::size_t p) {
  double x = starts.back().imag();
  if (variant == 2) {  // skip the first roughing: along the contour to the first pocket
    for (; p < segs_.size(); ++p) {
      if (seg::dive(segs_[p], at, -1e9, out_, p == 0)) break;
    }
    variant = 3;
  }
  while (p < segs_.size()) {
    spend();
    while (x - kTol > at.imag()) {
      x -= delta_;
      spend();
    }
    if (seg::dive(segs_[p], at, x, out_, p == 0)) {
      if (variant == 1) {  // no pockets: along the climbing parts of the contour to the end
        for (; p < segs_.size(); ++p) seg::climb_only(segs_[p], at, out_);
        return;
      }
      for (; p < segs_.size(); ++p) {
        if (!seg::climb(segs_[p], at, out_)) continue;
        if (variant == 3) {
          if (at.imag() > starts.back().imag() && starts.size() > 1) starts.pop_back();
          if (starts.size() == 1) starts.push_back(at);
        }
        if (++pockets_ > kMaxPockets) throw ProfileError{"too many pockets"};
        pocket(variant, at, p);
        return;
      }
      return;
    }
    if (p + 1 == segs_.size()) return;
    if (std::fabs(at.imag() - x) > kTol || segs_[p].end == at) {
      ++p;  // the pass height is beyond this segment
      continue;
    }
    if (!cut_pass(at, p, x))
      throw ProfileError{"the roughing pass at this height meets no profile"};
  }
}

// The profile from `start`, turned if asked, mirrored to run towards −Z and −X, its corners
// finished; it must then be monotonic.
Shape prepared(Profile profile, Pt start, bool turn) {
  Shape shape{std::move(profile)};
  shape.segs.front().start = start;
  if (turn) shape.turn();
  shape.normalise();
  shape.finish_corners();
  shape.check_monotonic();
  return shape;
}

// A profile that is not monotonic along Z is one along X (a face): G70 turns it.
bool along_x(const Profile& profile) {
  Shape probe{Profile(profile.begin() + 1, profile.end())};
  probe.normalise();
  return std::ranges::any_of(probe.segs, [](const Seg& s) { return !seg::monotonic(s); });
}
}  // namespace

void rough(Profile profile, const RoughingParams& p, MoveSink& out) {
  if (profile.size() < 2) return;
  Shape shape = prepared(std::move(profile), p.start, p.facing);
  shape.add_distance(p.allowance);
  for (Seg& s : shape.segs) seg::shift(s, p.shift);
  Oriented oriented(out, shape.state);
  Profile& segs = shape.segs;
  oriented.rapid(segs.front().start);
  // Close the profile back up to the start's height.
  if (segs.back().end.imag() < segs.front().start.imag()) {
    segs.push_back(line_seg(segs.back().end, {segs.back().end.real(), segs.front().start.imag()}));
  }
  Roughing r(segs, oriented, std::max(p.depth, 2 * kTol), p.retract);
  r.starts.push_back(segs.front().start);
  r.pocket(p.variant, segs.front().start, 0);
}

void finish(Profile profile, const FinishingParams& p, MoveSink& out) {
  if (profile.size() < 2) return;
  profile.front().start = p.start;
  const bool turn = along_x(profile);
  const Shape shape = prepared(std::move(profile), p.start, turn);
  Oriented oriented(out, shape.state);
  for (int pass = p.passes; pass > 0; --pass) {
    const double distance =
        (pass - 1) * (p.first_allowance - p.last_allowance) / p.passes + p.last_allowance;
    Shape path = shape;
    path.add_distance(distance);
    oriented.rapid(path.segs.front().start);
    oriented.rapid(path.segs.front().end);
    for (std::size_t i = 1; i < path.segs.size(); ++i) seg::draw(path.segs[i], oriented);
  }
}

}  // namespace cncore::interp::lathe
