// Internal: the reference-value analysis (the seed's section 11) and the interpolation shared
// by the limit check and the run.
#pragma once

#include <cstdint>

#include "tables/table.hpp"

namespace cncore::tables::detail {

// Reads a table row by row and turns each row into an effective control point, following the
// seed's flow chart (Fig. 4, steps SA01–SA10):
//   SFTCAN → shift flag off; clear: amount := 0 (written values again); rebase: the running
//            reference is reset by the amount (offset kept, amount := 0)
//   SFT a  → shift flag on; amount += a (a read from P/#/R when the row is read)
//   ref_effective = L_written + offset (+ repetition offset for CYCLIC tables)
// The first point is the start of the reference: if the first row is later, an implicit start
// point (start reference, start position) comes first. A CYCLIC table repeats rows; each
// repetition starts with a fresh shift state and is placed so that its first row coincides
// with the previous repetition's last row (one shared point).
class Analyzer {
 public:
  Analyzer(const Table& table, CancelMode mode, double start_ref, const AxisVec& start_pos,
           std::uint32_t repetitions);

  // The next control point, with indirect amounts read at time t_s. False at the end.
  // Throws InputError when a reference does not increase or an amount is undefined.
  bool next(const Values& values, double t_s, EffectivePoint& out);

 private:
  double analyse_row(const Row& row, const Values& values, double t_s);

  const Table* table_;
  CancelMode mode_;
  double start_ref_;
  AxisVec start_pos_;
  AxisVec modal_;
  std::uint32_t repetitions_;

  std::size_t row_ = 0;
  std::uint32_t rep_ = 0;
  bool shifting_ = false;
  double amount_ = 0;  // accumulated SFT amount
  double offset_ = 0;  // written → effective reference offset (amount, minus what a rebase kept)
  double rep_offset_ = 0;
  bool have_prev_ = false;
  double prev_ref_ = 0;
  std::uint32_t prev_line_ = 0;
  bool pending_ = false;
  EffectivePoint pending_point_;
};

double value_of_signal(const Values& values, int number, double t_s, bool& found);

// Fritsch–Carlson tangent (dp/dref) at b between a and c: 0 at a local extremum or flat side,
// else the weighted harmonic mean of the two secant slopes (keeps the curve monotone).
inline double pchip_tangent(double ra, double pa, double rb, double pb, double rc, double pc) {
  double h1 = rb - ra, h2 = rc - rb;
  double d1 = (pb - pa) / h1, d2 = (pc - pb) / h2;
  if (d1 * d2 <= 0) return 0;
  double w1 = 2 * h2 + h1, w2 = h2 + 2 * h1;
  return (w1 + w2) / (w1 / d1 + w2 / d2);
}

// Cubic Hermite on one segment, u ∈ [0, 1], h = reference span, m0/m1 tangents per reference
// unit: p(u) = h00 p0 + h10 h m0 + h01 p1 + h11 h m1.
inline double hermite(double p0, double p1, double m0, double m1, double h, double u) {
  double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * h * m0 + (-2 * u3 + 3 * u2) * p1 +
         (u3 - u2) * h * m1;
}

// Largest |dp/dref| and |d²p/dref²| on a Hermite segment. p'' is linear in u, so its extreme
// is at an end; p' is quadratic, so its extreme is at an end or where p'' = 0.
struct SegmentExtremes {
  double slope = 0;      // units per reference unit
  double curvature = 0;  // units per reference unit²
};
SegmentExtremes hermite_extremes(double p0, double p1, double m0, double m1, double h);

}  // namespace cncore::tables::detail
