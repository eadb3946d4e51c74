// Segment geometry of the lathe cycles' profiles (lathe_profile.hpp). Points are z + i·x; a
// line's left normal is i·(start − end)/|start − end|, an arc's radius grows with an offset
// on its outer side (ccw) and shrinks on the inner one.
#include "interpreter/lathe_profile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace cncore::interp::lathe {

namespace {
constexpr Pt kI{0, 1};

// Is p (on the arc's circle) within the arc's sweep?
bool on_arc(const Seg& s, Pt p) {
  const double from_start = std::imag(std::conj(s.start - s.centre) * (p - s.centre));
  const double to_end = std::imag(std::conj(s.end - s.centre) * (p - s.centre));
  if (s.ccw) return from_start >= -seg::kTol && to_end <= seg::kTol;
  return from_start <= seg::kTol && to_end >= -seg::kTol;
}

// A counter-clockwise arc that would pass its top (the highest X, above the centre) ends
// there: beyond it the profile descends.
Pt arc_top_or_end(const Seg& s) {
  if (s.end.real() >= s.centre.real()) return s.end;
  return {s.centre.real(), s.centre.imag() + std::abs(s.start - s.centre)};
}

// Where line `l` meets the circle about `c` through `on`: of its two crossings, the one
// nearer to `near`. `origin` and `rot` put the line on the real axis.
Pt line_circle(Pt origin, Pt rot, Pt c, Pt on, Pt near) {
  const Pt pc = (c - origin) * rot;
  const Pt pe = (on - origin) * rot;
  double b = std::norm(pc - pe) - pc.imag() * pc.imag();
  b = b < 0 ? 0 : std::sqrt(b);
  const Pt s1 = (pc.real() + b) / rot + origin;
  const Pt s2 = (pc.real() - b) / rot + origin;
  return std::abs(near - s1) < std::abs(near - s2) ? s1 : s2;
}
}  // namespace

Seg line_seg(Pt start, Pt end) {
  Seg s;
  s.start = start;
  s.end = end;
  return s;
}

Seg arc_seg(bool ccw, Pt start, Pt centre, Pt end) {
  Seg s;
  s.kind = SegKind::kArc;
  s.ccw = ccw;
  s.start = start;
  s.centre = centre;
  s.end = end;
  return s;
}

namespace seg {

void offset(Seg& s, double d) {
  if (!s.round()) {
    const Pt n = kI * d * (s.start - s.end) / std::abs(s.start - s.end);
    s.start += n;
    s.end += n;
    return;
  }
  const double r = std::abs(s.start - s.centre);
  const double k = (r + (s.ccw ? d : -d)) / r;
  s.start = k * (s.start - s.centre) + s.centre;
  s.end = k * (s.end - s.centre) + s.centre;
}

double size(const Seg& s) {
  if (!s.round()) return std::abs(s.start - s.end);
  return std::min(std::abs(s.start - s.end), std::abs(s.start - s.centre));
}

bool monotonic(const Seg& s) {
  const double dz = (s.end - s.start).real();
  if (!s.round()) return dz <= 1e-3;
  if (s.finish != 0) return true;  // a corner not yet finished
  const double entry = (s.start - s.centre).imag(), exit = (s.end - s.centre).imag();
  // Within one half of the circle: the upper half for G3, the lower for G2.
  if (s.ccw) return entry >= -1e-3 && exit >= -1e-3 && dz <= -1e-3;
  return entry <= 1e-3 && exit <= 1e-3 && dz <= -1e-3;
}

void flip_x(Seg& s) {
  s.start = std::conj(s.start);
  s.end = std::conj(s.end);
  s.centre = std::conj(s.centre);
  if (s.round()) s.ccw = !s.ccw;
}

void flip_z(Seg& s) {
  s.start = -std::conj(s.start);
  s.end = -std::conj(s.end);
  s.centre = -std::conj(s.centre);
  if (s.round()) s.ccw = !s.ccw;
}

void turn(Seg& s) {
  s.start = -s.start * kI;
  s.end = -s.end * kI;
  s.centre = -s.centre * kI;
}

void shift(Seg& s, Pt d) {
  s.start += d;
  s.end += d;
  s.centre += d;
}

void hits_at_x(const Seg& s, double x, Hits& out) {
  if (!s.round()) {
    if (std::min(s.start.imag(), s.end.imag()) > x + kTol ||
        std::max(s.start.imag(), s.end.imag()) < x - kTol) {
      return;
    }
    if (std::fabs((s.start - s.end).imag()) < kTol) {  // along Z: both ends
      out.push_back(s.start.real());
      out.push_back(s.end.real());
    } else {
      const double t = (x - s.start.imag()) / (s.end.imag() - s.start.imag());
      out.push_back(t * (s.end.real() - s.start.real()) + s.start.real());
    }
    return;
  }
  // (x − xc)² + (z − zc)² = r²: z = zc ± √(r² − (x − xc)²)
  const double r = std::abs(s.start - s.centre);
  double q = -(x - r - s.centre.imag()) * (x + r - s.centre.imag());
  if (q < -kTol) return;
  q = std::sqrt(std::max(q, 0.0));
  for (const double z : {s.centre.real() + q, s.centre.real() - q}) {
    if (on_arc(s, Pt{z, x})) out.push_back(z);
  }
}

// Moves prev.end and next.start to the intersection of the two curves (for two arcs: the
// crossing on the left of prev's centre → next's centre, by the law of cosines).
void join(Seg& prev, Seg& next) {
  if (!next.round() && !prev.round()) {
    const Pt rot = std::conj(next.start - next.end) / std::abs(next.start - next.end);
    const Pt ps = (prev.start - next.end) * rot, pe = (prev.end - next.end) * rot;
    if ((ps - pe).imag() == 0) throw ProfileError{"cannot intersect parallel lines"};
    const double f = ps.imag() / (ps - pe).imag();
    next.start = prev.end = (ps + f * (pe - ps)) / rot + next.end;
  } else if (!next.round()) {  // an arc, then a line
    if (std::abs(next.start - prev.end) < kTol) return;
    const Pt rot = std::conj(next.start - next.end) / std::abs(next.start - next.end);
    next.start = prev.end = line_circle(next.end, rot, prev.centre, prev.end, next.start);
  } else if (!prev.round()) {  // a line, then an arc
    if (std::abs(next.start - prev.end) < kTol) return;
    const Pt rot = std::conj(prev.start - prev.end) / std::abs(prev.start - prev.end);
    next.start = prev.end = line_circle(prev.end, rot, next.centre, next.end, next.start);
  } else {
    const double a = std::abs(next.start - next.centre);
    const double b = std::abs(prev.start - prev.centre);
    const double c = std::abs(next.centre - prev.centre);
    const double cos_b = (c * c + a * a - b * b) / 2.0 / a / c;
    const Pt rot{cos_b, std::sqrt(1 - std::min(1.0, cos_b * cos_b))};
    next.start = prev.end = rot * (prev.centre - next.centre) / c * a + next.centre;
  }
}

// A rounded or chamfered corner between prev and next: both are offset by the corner's size
// towards the inside of the corner (the side where the offset curves still meet), their
// intersection is the centre of the rounding, and its feet on the two curves the corner's
// ends.
Pt finish_corner(Seg& corner, Seg& prev, Seg& next) {
  auto offset_pair = [&](double d) {
    Seg p = prev, n = next;
    offset(p, d);
    offset(n, d);
    return std::pair{p, n};
  };
  auto [p, n] = offset_pair(corner.finish);
  if ((p.end - n.start).real() > 1e-2) {
    corner.finish = -corner.finish;
    std::tie(p, n) = offset_pair(corner.finish);
  }
  if ((p.end - n.start).real() > 1e-2) {
    throw ProfileError{
        fmt::format("corner finish failed at Z{:.4f} X{:.4f}", prev.end.real(), prev.end.imag())};
  }
  join(p, n);
  const Pt centre = (p.end + n.start) / 2.0;
  offset(p, -corner.finish);
  offset(n, -corner.finish);
  corner.start = prev.end = p.end;
  corner.end = next.start = n.start;
  return centre;
}

void draw(const Seg& s, MoveSink& out) {
  if (s.round()) {
    out.arc(s.ccw, s.centre, s.end);
  } else {
    out.feed(s.end);
  }
}

bool dive(const Seg& s, Pt& at, double x, MoveSink& out, bool rapid) {
  if (!s.round()) {
    if (s.start.imag() <= s.end.imag() + kTol) return true;
    Pt to = s.end;
    if (x >= s.end.imag()) {
      Hits hits;
      hits_at_x(s, x, hits);
      if (hits.empty()) throw ProfileError{"X beyond the segment in a straight dive"};
      to = {hits.front(), x};
    }
    if (rapid) {
      out.rapid(to);
    } else {
      out.feed(to);
    }
    at = to;
    return false;
  }
  if (std::abs(at - s.end) < kTol || (at - s.end).real() <= kTol) {
    at = s.end;
    return false;
  }
  Hits hits;
  hits_at_x(s, x, hits);
  if (hits.empty()) hits_at_x(s, x - kTol, hits);
  Pt to = s.end;
  if (s.ccw) {  // G3: descends before its centre
    if (at.real() - kTol > s.centre.real()) return true;
    if (!hits.empty() && hits.back() <= s.centre.real()) to = {hits.back(), x};
  } else {  // G2: descends after its centre
    if (at.real() <= s.centre.real()) return true;
    if (!hits.empty()) {
      if (hits.front() < s.centre.real()) return false;  // met on the climbing side only
      to = {hits.front(), x};
    }
  }
  out.arc(s.ccw, s.centre, to);
  at = to;
  return false;
}

bool climb(const Seg& s, Pt& at, MoveSink& out) {
  if (!s.round()) {
    if (s.end.imag() + kTol < s.start.imag()) return true;
    if (std::abs(at - s.start) > kTol) throw ProfileError{"lost the profile while climbing"};
    out.feed(s.end);
    at = s.end;
    return false;
  }
  if (!s.ccw) {
    if (at.real() > s.centre.real()) return true;
    if (std::abs(at - s.end) > 1e-3) out.arc(s.ccw, s.centre, s.end);
    at = s.end;
    return false;
  }
  if (at.real() < s.centre.real()) return true;
  const Pt to = arc_top_or_end(s);
  if (std::abs(at - to) > 1e-3) out.arc(s.ccw, s.centre, to);
  at = to;
  return true;
}

void climb_only(const Seg& s, Pt& at, MoveSink& out) {
  if (!s.round() && s.end.imag() < s.start.imag()) return;
  Hits hits;
  hits_at_x(s, at.imag(), hits);
  if (hits.empty()) return;
  if (!s.round()) {
    at.real(hits.front());
    out.feed(at);
    out.feed(s.end);
    at = s.end;
    return;
  }
  const double z = s.ccw ? hits.front() : hits.back();
  if (s.ccw ? z < s.centre.real() : z > s.centre.real()) return;
  at.real(z);
  out.feed(at);
  const Pt to = s.ccw ? arc_top_or_end(s) : s.end;
  if (std::abs(at - to) > 1e-3) out.arc(s.ccw, s.centre, to);
  at = to;
}

}  // namespace seg

}  // namespace cncore::interp::lathe
