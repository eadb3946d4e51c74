#include "simulation/cutting/heightmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cncore::cut {

double ToolProfile::height_at(double r_mm) const {
  const double a = radius_mm - corner_mm;
  if (r_mm <= a) return 0;
  const double u = r_mm - a;
  const double q = corner_mm * corner_mm - u * u;
  return corner_mm - std::sqrt(q > 0 ? q : 0);
}

HeightMap::HeightMap(double x0_mm, double y0_mm, double cell_mm, std::size_t nx, std::size_t ny,
                     double bottom_z_mm, double top_z_mm)
    : x0_(x0_mm),
      y0_(y0_mm),
      cell_(cell_mm),
      nx_(nx),
      ny_(ny),
      bottom_(bottom_z_mm),
      top_(top_z_mm),
      max_h_(static_cast<float>(top_z_mm)),
      h_(nx * ny, static_cast<float>(top_z_mm)) {}

HeightMap HeightMap::from_stock(const StockConfig& s) {
  // The same cell count as the configuration's memory check.
  const auto n = [&s](double size) {
    return static_cast<std::size_t>(std::max(1.0, std::ceil(size / s.cell_mm - 1e-9)));
  };
  return {s.min_mm[0],
          s.min_mm[1],
          s.cell_mm,
          n(s.size_mm[0]),
          n(s.size_mm[1]),
          s.min_mm[2],
          s.min_mm[2] + s.size_mm[2]};
}

double HeightMap::volume_mm3() const {
  double v = 0;
  for (float h : h_) v += static_cast<double>(h) - bottom_;
  return v * cell_ * cell_;
}

namespace {

// Parameter interval [tl, th] ∩ [0, 1] of the segment w − t·d (X-Y, relative to the cell)
// within distance R: lxy2·t² − 2(w·d)·t + |w|² − R² ≤ 0. False when empty.
bool feasible(double wx, double wy, double dx, double dy, double lxy2, double r2, double& tl,
              double& th) {
  if (lxy2 <= 1e-24) {  // vertical move: the whole segment or nothing
    tl = 0;
    th = 1;
    return wx * wx + wy * wy <= r2;
  }
  const double wd = wx * dx + wy * dy;
  const double disc = wd * wd - lxy2 * (wx * wx + wy * wy - r2);
  if (disc < 0) return false;
  const double s = std::sqrt(disc);
  tl = std::max(0.0, (wd - s) / lxy2);
  th = std::min(1.0, (wd + s) / lxy2);
  return tl <= th;
}

}  // namespace

// Size: one pass over the footprint's rows and the cells of each row; the tool shapes' per-cell
// cases (flat, ball, bull nose) use the row geometry computed once, in the cutting simulation's
// innermost loop.
double HeightMap::sweep(const ToolProfile& tool, const Vec3& a, const Vec3& b) {
  const double R = tool.radius_mm;
  const double r2 = R * R;
  const double zmin = std::min(a.z, b.z);
  if (zmin >= static_cast<double>(max_h_)) return 0;  // entirely above the stock

  // Rows whose centres lie within the footprint's bounding box.
  const double by0 = std::min(a.y, b.y) - R, by1 = std::max(a.y, b.y) + R;
  const double bx0 = std::min(a.x, b.x) - R, bx1 = std::max(a.x, b.x) + R;
  const double jlo = std::ceil((by0 - y0_) / cell_ - 0.5);
  const double jhi = std::floor((by1 - y0_) / cell_ - 0.5);
  const double ilo_box = std::ceil((bx0 - x0_) / cell_ - 0.5);
  const double ihi_box = std::floor((bx1 - x0_) / cell_ - 0.5);
  const auto nxd = static_cast<double>(nx_), nyd = static_cast<double>(ny_);
  if (jhi < 0 || jlo > nyd - 1 || ihi_box < 0 || ilo_box > nxd - 1 || jlo > jhi) return 0;
  const auto j0 = static_cast<std::size_t>(std::max(0.0, jlo));
  const auto j1 = static_cast<std::size_t>(std::min(nyd - 1, jhi));

  const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  const double lxy2 = dx * dx + dy * dy;
  const bool has_dir = lxy2 > 1e-24;
  const bool horizontal = std::fabs(dz) <= 1e-12;
  // Unit normal of the X-Y direction: the footprint's straight edges are a ± R·n → b ± R·n.
  double nx = 0, ny = 0;
  if (has_dir) {
    const double l = std::sqrt(lxy2);
    nx = -dy / l;
    ny = dx / l;
  }
  const auto bottom_f = static_cast<float>(bottom_);
  const float zmin_f = std::max(static_cast<float>(zmin), bottom_f);
  const double l3 = std::sqrt(lxy2 + dz * dz);

  // The exact lowest tool-bottom height over the segment at a cell (w = cell − a in X-Y),
  // for a non-horizontal move. f(t) = a.z + t·dz + h(|w − t·d|) is convex in t.
  auto exact = [&](double wx, double wy, double xc, double yc, double lower_bound) {
    double tl = 0, th = 1;
    switch (tool.shape) {
      case ToolShape::kFlat: {
        // h = 0 inside the footprint: the lowest z on the feasible interval, at one of its ends.
        if (!feasible(wx, wy, dx, dy, lxy2, r2, tl, th)) return lower_bound;
        return a.z + dz * (dz > 0 ? tl : th);
      }
      case ToolShape::kBall: {
        // Ball centres run on A → B (tip + R). The vertical line through the cell meets the
        // capsule of radius R around A B lowest either on an end sphere or on the cylinder:
        // |v|² − (v·u)² = R² with v = (wx, wy, s), u the unit direction, a quadratic in s whose
        // lower root counts when its axial position v·u lies within [0, |AB|].
        double best = std::numeric_limits<double>::infinity();
        const double wa2 = wx * wx + wy * wy;
        if (wa2 <= r2) best = a.z + R - std::sqrt(r2 - wa2);
        const double ux = xc - b.x, uy = yc - b.y;
        const double wb2 = ux * ux + uy * uy;
        if (wb2 <= r2) best = std::min(best, b.z + R - std::sqrt(r2 - wb2));
        const double ex = dx / l3, ey = dy / l3, ez = dz / l3;
        const double a2 = 1 - ez * ez;
        if (a2 > 1e-12) {
          const double vu = wx * ex + wy * ey;
          const double b2 = -2 * ez * vu;
          const double c2 = wa2 - vu * vu - r2;
          const double disc = b2 * b2 - 4 * a2 * c2;
          if (disc >= 0) {
            const double s = (-b2 - std::sqrt(disc)) / (2 * a2);
            const double axial = vu + s * ez;
            if (axial >= 0 && axial <= l3) best = std::min(best, a.z + R + s);
          }
        }
        return std::isfinite(best) ? best : lower_bound;
      }
      case ToolShape::kBullNose:
        break;
    }
    // Bull nose: f is convex, so its minimum on [tl, th] is where f' changes sign (or an end).
    // f'(t) = dz + h'(r)·r'(t), h'(r) = (r − a)/√(rc² − (r − a)²) beyond the flat centre,
    // r'(t) = −(w − t·d)·d / r. The root is found by the Illinois variant of regula falsi
    // (bisection while an end value is infinite, at the footprint's rim): a few evaluations.
    if (!feasible(wx, wy, dx, dy, lxy2, r2, tl, th)) return lower_bound;
    auto f = [&](double t) {
      const double px = wx - t * dx, py = wy - t * dy;
      return a.z + t * dz + tool.height_at(std::sqrt(px * px + py * py));
    };
    const double flat = tool.flat_mm(), rc = tool.corner_mm;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    auto fp = [&](double t) {
      const double px = wx - t * dx, py = wy - t * dy;
      const double r = std::sqrt(px * px + py * py);
      if (r <= flat || r == 0) return dz;
      const double rp = -(px * dx + py * dy) / r;
      const double u = r - flat;
      const double q = rc * rc - u * u;
      if (q <= 0) return rp > 0 ? kInf : (rp < 0 ? -kInf : dz);
      return dz + u / std::sqrt(q) * rp;
    };
    double lo = tl, hi = th;
    double glo = fp(lo), ghi = fp(hi);
    if (glo >= 0) return f(lo);
    if (ghi <= 0) return f(hi);
    double t = 0.5 * (lo + hi);
    int side = 0;
    for (int it = 0; it < 100; ++it) {
      t = std::isfinite(glo) && std::isfinite(ghi) ? lo - glo * (hi - lo) / (ghi - glo)
                                                   : 0.5 * (lo + hi);
      if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
      const double g = fp(t);
      // Convexity: f(t) − min f ≤ |f'(t)|·(hi − lo); stop at 1e-9 mm.
      if (g == 0 || std::fabs(g) * (hi - lo) < 1e-9 || hi - lo < 1e-15) break;
      if (g < 0) {
        lo = t;
        glo = g;
        if (side == -1) ghi *= 0.5;
        side = -1;
      } else {
        hi = t;
        ghi = g;
        if (side == 1) glo *= 0.5;
        side = 1;
      }
    }
    return f(t);
  };

  // h(√d2) with one square root at most (this runs for most cells under the tool).
  const double flat_r2 = tool.flat_mm() * tool.flat_mm();
  auto lift = [&](double d2) {
    switch (tool.shape) {
      case ToolShape::kFlat:
        return 0.0;
      case ToolShape::kBall:
        return R - std::sqrt(std::max(0.0, r2 - d2));
      case ToolShape::kBullNose:
        break;
    }
    return d2 <= flat_r2 ? 0.0 : tool.height_at(std::sqrt(d2));
  };

  double removed = 0;  // Σ Δh
  for (std::size_t j = j0; j <= j1; ++j) {
    const double yc = y_of(j);
    // The footprint (the convex hull of the two end discs) meets this row in [xl, xr]: the
    // extremes lie on the end circles or on the straight edges.
    double xl = std::numeric_limits<double>::infinity(), xr = -xl;
    auto disc = [&](double px, double py) {
      const double ey = yc - py;
      const double q = r2 - ey * ey;
      if (q < 0) return;
      const double s = std::sqrt(q);
      xl = std::min(xl, px - s);
      xr = std::max(xr, px + s);
    };
    disc(a.x, a.y);
    disc(b.x, b.y);
    if (has_dir) {
      for (const double sign : {1.0, -1.0}) {
        const double ex0 = a.x + sign * R * nx, ey0 = a.y + sign * R * ny;
        const double ex1 = b.x + sign * R * nx, ey1 = b.y + sign * R * ny;
        if (ey0 != ey1 && (yc - ey0) * (yc - ey1) <= 0) {
          const double x = ex0 + (yc - ey0) / (ey1 - ey0) * (ex1 - ex0);
          xl = std::min(xl, x);
          xr = std::max(xr, x);
        }
      }
    }
    if (!(xl <= xr)) continue;
    const double ilo = std::max(0.0, std::ceil((xl - x0_) / cell_ - 0.5));
    const double ihi = std::min(nxd - 1, std::floor((xr - x0_) / cell_ - 0.5));
    if (ilo > ihi) continue;
    const auto i0 = static_cast<std::size_t>(ilo), i1 = static_cast<std::size_t>(ihi);
    float* row = &h_[j * nx_];
    if (tool.shape == ToolShape::kFlat && horizontal) {
      // Every cell of the footprint goes down to the (flat) tool bottom.
      for (std::size_t i = i0; i <= i1; ++i) {
        if (row[i] > zmin_f) {
          removed += static_cast<double>(row[i] - zmin_f);
          row[i] = zmin_f;
        }
      }
      continue;
    }
    const double wy = yc - a.y;
    for (std::size_t i = i0; i <= i1; ++i) {
      if (row[i] <= zmin_f) continue;  // already at or below the lowest the tool gets
      const double xc = x_of(i);
      const double wx = xc - a.x;
      // Distance from the cell to the segment in X-Y; zmin + h(distance) bounds the tool
      // height from below (and is exact for a horizontal move).
      double t = has_dir ? (wx * dx + wy * dy) / lxy2 : 0;
      t = std::clamp(t, 0.0, 1.0);
      const double px = wx - t * dx, py = wy - t * dy;
      const double d2 = px * px + py * py;
      if (d2 > r2) continue;
      const double lower = zmin + lift(d2);
      if (static_cast<double>(row[i]) <= lower) continue;
      const double z = horizontal ? lower : exact(wx, wy, xc, yc, lower);
      const float zf = std::max(static_cast<float>(z), bottom_f);
      if (zf < row[i]) {
        removed += static_cast<double>(row[i] - zf);
        row[i] = zf;
      }
    }
  }
  return removed * cell_ * cell_;
}

}  // namespace cncore::cut
