// Arc geometry in the active plane. A plane is described by its two in-plane axes (first,
// second) and its normal axis, chosen so that (first, second, normal) is right-handed:
//   G17: (X, Y, Z), centre words I J     G18: (Z, X, Y), centre words K I
//   G19: (Y, Z, X), centre words J K
// so a counter-clockwise arc in (first, second) coordinates (G3) turns positively about the
// normal axis, and G2 turns negatively. All lengths here are mm.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace cncore::interp {

struct Vec2 {
  double a = 0, b = 0;  // (first, second) plane coordinates

  friend Vec2 operator+(Vec2 p, Vec2 q) { return {p.a + q.a, p.b + q.b}; }
  friend Vec2 operator-(Vec2 p, Vec2 q) { return {p.a - q.a, p.b - q.b}; }
  friend Vec2 operator*(double k, Vec2 p) { return {k * p.a, k * p.b}; }
};
inline double dot(Vec2 p, Vec2 q) {
  return p.a * q.a + p.b * q.b;
}
inline double cross(Vec2 p, Vec2 q) {  // z of the 3-D cross product
  return p.a * q.b - p.b * q.a;
}
inline double norm(Vec2 p) {
  return std::hypot(p.a, p.b);
}

enum class Plane : std::uint8_t { kXY, kZX, kYZ };

struct PlaneAxes {
  std::size_t first, second, normal;          // axis indices (kX, kY, kZ)
  char first_word, second_word, normal_word;  // centre-offset letters ('i', 'j', 'k')
};
PlaneAxes plane_axes(Plane plane);
const char* plane_gcode(Plane plane);  // "G17", "G18", "G19"

// Result of a geometric check: ok, or a message for an InputError.
struct ArcCheck {
  bool ok = true;
  const char* message = "";
};

// R form. Centre of the arc of radius |r| from s to e (LinuxCNC arc_data_r):
//   m = (s + e)/2, h = |e − s|/2, d = sqrt(r² − h²)
//   c = m + d·n̂, where n̂ ⟂ (e − s) is on the left of the chord for a short CCW arc
//   (or a long CW arc, r < 0) and on the right otherwise.
// h > |r| + tolerance_mm: impossible radius. h slightly above |r| (within tolerance): half
// circle, c = m. s == e: error (an R arc cannot be a full circle).
ArcCheck centre_from_radius(Vec2 s, Vec2 e, double r, bool ccw, double tolerance_mm, Vec2& c);

// Centre form (I J K). The radii at start and end, r0 = |s − c| and r1 = |e − c|, must agree
// (LinuxCNC arc_data_ijk): error when |r1 − r0| > 100·abs_tol_mm, or when both
// |r1 − r0| > abs_tol_mm and |r1 − r0| / max(r0, r1) > rel_tol. An accepted centre is then
// moved onto the perpendicular bisector of the chord (its nearest point there),
//   c' = m + ((c − m)·n̂) n̂,
// so that the emitted arc has exactly equal radii at both ends.
ArcCheck check_centre(Vec2 s, Vec2 e, Vec2& c, double abs_tol_mm, double rel_tol);

// Signed swept angle (rad, CCW positive) from s to e about c, plus `turns` full extra turns.
// s == e (within 1e-9 mm) is a full circle.
double arc_sweep(Vec2 s, Vec2 e, Vec2 c, bool ccw, std::uint32_t turns);

// Bounding box of the arc in the plane: start/end plus every axis-aligned extreme
// (angles 0, 90, 180, 270 degrees) that the sweep passes.
void arc_bounds(Vec2 s, Vec2 e, Vec2 c, double sweep_rad, Vec2& lo, Vec2& hi);

}  // namespace cncore::interp
