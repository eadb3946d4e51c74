// One branch of the direction feed correction (spec 03): the coefficient C as a function of the
// direction ratio FI, written as a muParser expression in FI, F (programmed feed, mm/min) and D
// (tool diameter, mm), or as a piecewise-linear table of (FI, C) points. A plain value in the
// machine configuration; CorrectionEvaluator compiles it (muParser is included in the .cpp only).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cncore {

struct CorrectionLaw {
  std::string formula;                       // used when `table` is empty
  std::vector<std::array<double, 2>> table;  // (FI, C), FI strictly increasing; flat outside

  bool is_table() const { return !table.empty(); }
  friend bool operator==(const CorrectionLaw&, const CorrectionLaw&) = default;
};

// A formula that does not parse or cannot be evaluated. `position`: 0-based character of the
// formula where muParser found the problem, −1 when unknown.
class CorrectionLawError : public std::runtime_error {
 public:
  CorrectionLawError(const std::string& message, int position)
      : std::runtime_error(message), position_(position) {}
  int position() const { return position_; }

 private:
  int position_;
};

class CorrectionEvaluator {
 public:
  // Compiles the formula (throws CorrectionLawError on a syntax error or an unknown variable).
  explicit CorrectionEvaluator(const CorrectionLaw& law);
  ~CorrectionEvaluator();
  CorrectionEvaluator(CorrectionEvaluator&&) noexcept;
  CorrectionEvaluator& operator=(CorrectionEvaluator&&) noexcept;
  CorrectionEvaluator(const CorrectionEvaluator&) = delete;
  CorrectionEvaluator& operator=(const CorrectionEvaluator&) = delete;

  // C at direction ratio fi, programmed feed f (mm/min), tool diameter d (mm). May return a
  // non-finite or non-positive value; the caller decides (see find_bad_coefficient).
  double operator()(double fi, double feed_mm_min, double diameter_mm) const;
  // Whether the formula reads F (the load-time check then also scans the feed range).
  bool uses_feed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A point where the law gives a coefficient that is not finite or not > 0.
struct BadCoefficient {
  double fi = 0, feed_mm_min = 0, c = 0;
};

// Scans FI over [fi_lo, fi_hi] on a grid of 2000 steps (both ends included) and, when the
// formula reads F, the feeds 1 mm/min and max_feed·k/16 (k = 1 … 16); returns the first bad point.
std::optional<BadCoefficient> find_bad_coefficient(const CorrectionLaw& law, double fi_lo,
                                                   double fi_hi, double max_feed_mm_min,
                                                   double diameter_mm);

}  // namespace cncore
