#include "config/correction_law.hpp"

#include <muParser.h>

#include <algorithm>
#include <cmath>

namespace cncore {

struct CorrectionEvaluator::Impl {
  CorrectionLaw law;
  // muParser binds variables by address: they live here, next to the parser, and the Impl is
  // never copied (the evaluator is move-only through the pointer).
  mutable double fi = 0, feed = 0, diameter = 0;
  mutable mu::Parser parser;
  bool reads_feed = false;
};

namespace {

double table_value(const std::vector<std::array<double, 2>>& t, double fi) {
  if (fi <= t.front()[0]) return t.front()[1];
  if (fi >= t.back()[0]) return t.back()[1];
  const auto it = std::upper_bound(
      t.begin(), t.end(), fi, [](double x, const std::array<double, 2>& p) { return x < p[0]; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  // Linear between the two points around fi.
  return a[1] + (b[1] - a[1]) * (fi - a[0]) / (b[0] - a[0]);
}

}  // namespace

CorrectionEvaluator::CorrectionEvaluator(const CorrectionLaw& law)
    : impl_(std::make_unique<Impl>()) {
  impl_->law = law;
  if (law.is_table()) return;
  try {
    mu::Parser& p = impl_->parser;
    p.DefineVar("FI", &impl_->fi);
    p.DefineVar("F", &impl_->feed);
    p.DefineVar("D", &impl_->diameter);
    p.SetExpr(law.formula);
    // Parses (and reports syntax errors and unknown names) now rather than at the first use.
    const mu::varmap_type used = p.GetUsedVar();
    impl_->reads_feed = used.count("F") > 0;
  } catch (const mu::Parser::exception_type& e) {
    throw CorrectionLawError(e.GetMsg(), e.GetPos());
  }
}

CorrectionEvaluator::~CorrectionEvaluator() = default;
CorrectionEvaluator::CorrectionEvaluator(CorrectionEvaluator&&) noexcept = default;
CorrectionEvaluator& CorrectionEvaluator::operator=(CorrectionEvaluator&&) noexcept = default;

double CorrectionEvaluator::operator()(double fi, double feed_mm_min, double diameter_mm) const {
  if (impl_->law.is_table()) return table_value(impl_->law.table, fi);
  impl_->fi = fi;
  impl_->feed = feed_mm_min;
  impl_->diameter = diameter_mm;
  try {
    return impl_->parser.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw CorrectionLawError(e.GetMsg(), e.GetPos());
  }
}

bool CorrectionEvaluator::uses_feed() const {
  return impl_->reads_feed;
}

std::optional<BadCoefficient> find_bad_coefficient(const CorrectionLaw& law, double fi_lo,
                                                   double fi_hi, double max_feed_mm_min,
                                                   double diameter_mm) {
  const CorrectionEvaluator eval(law);
  std::vector<double> feeds{max_feed_mm_min};
  if (eval.uses_feed()) {
    feeds = {1.0};
    for (int k = 1; k <= 16; ++k) feeds.push_back(max_feed_mm_min * k / 16.0);
  }
  constexpr int kSteps = 2000;
  for (const double f : feeds) {
    for (int i = 0; i <= kSteps; ++i) {
      // Both ends exactly (fi_hi is not reached by accumulation).
      const double fi = i == kSteps ? fi_hi : fi_lo + (fi_hi - fi_lo) * i / kSteps;
      const double c = eval(fi, f, diameter_mm);
      if (!std::isfinite(c) || c <= 0) return BadCoefficient{fi, f, c};
    }
  }
  return std::nullopt;
}

}  // namespace cncore
