// Small value types shared by every pipeline stage: positions of all axes and 3-D vectors.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>

namespace cncore {

// Axis slots, fixed order. Linear axes in mm, rotary axes in degrees, machine coordinates.
enum Axis : std::size_t { kX = 0, kY, kZ, kA, kB, kC };
inline constexpr std::size_t kMaxAxes = 6;
inline constexpr std::array<char, kMaxAxes> kAxisLetters = {'X', 'Y', 'Z', 'A', 'B', 'C'};

struct Vec3 {
  double x = 0, y = 0, z = 0;

  friend constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend constexpr Vec3 operator*(double k, Vec3 a) { return {k * a.x, k * a.y, k * a.z}; }
  friend constexpr bool operator==(Vec3 a, Vec3 b) = default;
};
constexpr double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a) {
  return std::sqrt(dot(a, a));
}
// v / |v|, or the zero vector for a vector of no length.
inline Vec3 unit_or_zero(Vec3 v) {
  const double n = norm(v);
  return n > 0 ? (1 / n) * v : Vec3{};
}
// Component i (0: x, 1: y, 2: z) of v.
constexpr double component(const Vec3& v, std::size_t i) {
  return i == 0 ? v.x : (i == 1 ? v.y : v.z);
}

// Position (or displacement) of every axis slot; unused slots stay 0.
struct AxisVec {
  std::array<double, kMaxAxes> v{};

  constexpr double& operator[](std::size_t i) { return v[i]; }
  constexpr double operator[](std::size_t i) const { return v[i]; }
  constexpr Vec3 xyz() const { return {v[kX], v[kY], v[kZ]}; }
  constexpr void set_xyz(Vec3 p) {
    v[kX] = p.x;
    v[kY] = p.y;
    v[kZ] = p.z;
  }
  friend constexpr AxisVec operator+(const AxisVec& a, const AxisVec& b) {
    AxisVec r;
    for (std::size_t i = 0; i < kMaxAxes; ++i) r.v[i] = a.v[i] + b.v[i];
    return r;
  }
  friend constexpr AxisVec operator-(const AxisVec& a, const AxisVec& b) {
    AxisVec r;
    for (std::size_t i = 0; i < kMaxAxes; ++i) r.v[i] = a.v[i] - b.v[i];
    return r;
  }
  friend constexpr AxisVec operator*(double k, const AxisVec& a) {
    AxisVec r;
    for (std::size_t i = 0; i < kMaxAxes; ++i) r.v[i] = k * a.v[i];
    return r;
  }
  friend constexpr bool operator==(const AxisVec& a, const AxisVec& b) = default;
};

}  // namespace cncore
