// The stock as a height map (Z-map): one height per cell of a regular X-Y grid, cell centres at
// x0 + (i + ½)·cell, y0 + (j + ½)·cell. A tool moving along a straight segment lowers every cell
// under its swept lower envelope to the envelope's height there; nothing else is touched.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "config/cutting_config.hpp"
#include "core/geometry.hpp"

namespace cncore::cut {

// The lower envelope of a rotating tool: its height above the tip at radial distance r,
// h(r) = 0 for r ≤ a (the flat centre, a = R − rc), rc − √(rc² − (r − a)²) for a < r ≤ R.
// Flat end mill: rc = 0; ball: rc = R; bull nose: 0 < rc < R. h is convex and non-decreasing,
// which makes the sweep along a line a convex problem in the line parameter.
struct ToolProfile {
  double radius_mm = 5;  // R
  double corner_mm = 0;  // rc
  ToolShape shape = ToolShape::kFlat;

  static ToolProfile of(const ToolSpec& tool) {
    return {tool.radius_mm(), tool.effective_corner_mm(), tool.shape};
  }
  double flat_mm() const { return radius_mm - corner_mm; }  // a
  double height_at(double r_mm) const;
};

class HeightMap {
 public:
  // A box stock: the map covers [x0, x0 + nx·cell) × [y0, y0 + ny·cell), heights start at
  // top_z and never go below bottom_z (a tool cutting through removes nothing underneath).
  HeightMap(double x0_mm, double y0_mm, double cell_mm, std::size_t nx, std::size_t ny,
            double bottom_z_mm, double top_z_mm);
  static HeightMap from_stock(const StockConfig& stock);

  // Sweeps the tool with its tip moving on the straight segment a → b (XYZ, mm) and lowers the
  // map: each cell within R of the segment (in X-Y) gets min(its height, min over the segment
  // of the tool's bottom height at the cell centre). Exact at the cell centres for straight
  // moves: closed form for flat and ball end mills, a convex 1-D minimisation (root of the
  // derivative by regula falsi, to 1e-9 mm) for the bull nose. Returns the removed volume, mm³ (Σ
  // Δh·cell²). No allocation; cost proportional to the cells under the swept footprint.
  double sweep(const ToolProfile& tool, const Vec3& a, const Vec3& b);

  std::size_t nx() const { return nx_; }
  std::size_t ny() const { return ny_; }
  double cell_mm() const { return cell_; }
  double x0_mm() const { return x0_; }
  double y0_mm() const { return y0_; }
  double bottom_z_mm() const { return bottom_; }
  double top_z_mm() const { return top_; }
  double x_of(std::size_t i) const { return x0_ + (static_cast<double>(i) + 0.5) * cell_; }
  double y_of(std::size_t j) const { return y0_ + (static_cast<double>(j) + 0.5) * cell_; }
  float at(std::size_t i, std::size_t j) const { return h_[j * nx_ + i]; }
  const std::vector<float>& heights() const { return h_; }  // row-major, row j = y index
  // Σ (h − bottom)·cell²: the material left, mm³.
  double volume_mm3() const;

 private:
  double x0_, y0_, cell_;
  std::size_t nx_, ny_;
  double bottom_, top_;
  float max_h_;  // highest cell (never rises): moves above it cut nothing
  std::vector<float> h_;
};

}  // namespace cncore::cut
