// The spline moves of the XY plane, as LinuxCNC reads them: G5 (cubic), G5.1 (quadratic) and the
// NURBS block G5.2 … G5.3. Each curve goes out as tangent-continuous arcs within the contour
// tolerance (interpreter/spline.hpp), so that the planner runs them at the speed of their
// curvature.
#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"
#include "interpreter/spline.hpp"

namespace cncore::interp {
namespace {

constexpr std::size_t kMaxNurbsPoints = 100000;
constexpr int kMaxNurbsOrder = 10;
// The contour tolerance below which the fit is not asked to go (a G64 P0 would make it endless).
constexpr double kMinSplineTolMm = 0.001;

bool is_spline(Motion m) {
  return m == Motion::kCubicSpline || m == Motion::kQuadSpline || m == Motion::kNurbs;
}

}  // namespace

double Interpreter::Impl::spline_tolerance_mm() const {
  const double tol = modal_.path_mode == PathMode::kBlend && modal_.tolerance_mm >= 0
                         ? modal_.tolerance_mm
                         : machine_.contour_tolerance_mm;
  return std::max(tol, kMinSplineTolMm);
}

bool Interpreter::Impl::spline_motion(const Words::Code* motion_word, bool have_axes,
                                      std::uint32_t col) {
  const Words& w = words_;
  const int code = motion_word != nullptr ? motion_word->code10 : -1;
  if (nurbs_open_ && motion_word != nullptr && code != 52 && code != 53) {
    fail(motion_word->col, fmt::format("the NURBS block (G5.2) is still open: close it with G5.3 "
                                       "before {}",
                                       code_text('G', code)));
  }
  if (code != 50) g5_chain_ = g5_chain_ && motion_word == nullptr;
  if (!is_spline(modal_.motion) && code != 53) return false;
  const std::string name = code >= 0                               ? code_text('G', code)
                           : modal_.motion == Motion::kCubicSpline ? "G5"
                           : modal_.motion == Motion::kQuadSpline  ? "G5.1"
                                                                   : "G5.2";
  if (modal_.plane != Plane::kXY) {
    fail(motion_word != nullptr ? motion_word->col : col,
         fmt::format("{} splines are in the XY plane only: program G17 first", name));
  }
  for (const char c : {'z', 'a', 'b', 'c', 'k', 'r'}) {
    if (w.has(c)) {
      fail(w[c].col, fmt::format("{} word with {}: a spline moves X and Y only",
                                 static_cast<char>(c - 'a' + 'A'), name));
    }
  }
  if (code == 53) {
    if (!nurbs_open_) fail(col, "G5.3 without a NURBS block (G5.2) to close");
    nurbs_end(col);
    modal_.motion = Motion::kNone;
    return true;
  }
  if (modal_.motion == Motion::kNurbs) {
    nurbs_point(code == 52, have_axes);
    return true;
  }
  // A G5 or G5.1 word asks for its curve (and its words) even without axis words: the curve
  // may end where it starts.
  if (have_axes || motion_word != nullptr)
    bezier_spline(modal_.motion == Motion::kCubicSpline, col);
  return true;
}

// G5 X Y [I J] P Q (cubic: control points start, start + (I, J), end + (P, Q), end) and G5.1 X Y
// I J (quadratic: start, start + (I, J), end). The offsets turn with the system's rotation.
void Interpreter::Impl::bezier_spline(bool cubic, std::uint32_t col) {
  const Words& w = words_;
  const bool has_i = w.has('i'), has_j = w.has('j');
  if (cubic) {
    if (!w.has('p') || !w.has('q')) {
      fail(col, "G5 needs both P and Q (the second control point, from the end point)");
    }
    if (has_i != has_j) {
      fail(w[has_i ? 'i' : 'j'].col,
           "G5 needs I and J together (the first control point, from the start), or neither");
    }
    if (!has_i && !(g5_chain_ && pos_ == g5_end_)) {
      fail(col, "G5 without I and J must follow another G5: the first of a series needs I and J");
    }
  } else {
    for (const char c : {'p', 'q'}) {
      if (w.has(c)) {
        fail(w[c].col, fmt::format("{} word with G5.1 (the quadratic spline takes I and J only)",
                                   static_cast<char>(c - 'a' + 'A')));
      }
    }
    if (w['i'].value == 0 && w['j'].value == 0) {
      fail(col, "G5.1 needs I or J (the control point, from the start), not both zero");
    }
  }
  move_feed_mm_min(0, col);  // the feed errors after the words, as LinuxCNC
  const AxisVec target = target_from_words(false);
  const double unit = modal_.length_unit_mm();
  const double rot = rotation_deg(modal_.coord_system);
  auto offset = [&](char a, char b) {
    const Vec2 d = rotated({w[a].value * unit, w[b].value * unit}, rot);
    return Vec3{d.a, d.b, 0};
  };
  const Vec3 s = pos_.xyz();
  Vec3 e = target.xyz();
  e.z = s.z;
  std::vector<Vec3> control{s};
  if (cubic) {
    control.push_back(has_i ? s + offset('i', 'j') : s - g5_pq_);
    g5_pq_ = offset('p', 'q');
    control.push_back(e + g5_pq_);
  } else {
    control.push_back(s + offset('i', 'j'));
  }
  control.push_back(e);
  emit_spline(PlaneSpline::bezier(control), target, col);
  g5_chain_ = cubic;
  g5_end_ = target;
}

// A line of the NURBS block: G5.2 [P weight] [L order] opens it with the current point as the
// first control point (P alone: that point's weight); X Y [P] adds a control point.
void Interpreter::Impl::nurbs_point(bool opens, bool have_axes) {
  const Words& w = words_;
  if (opens && !nurbs_open_) {
    nurbs_open_ = true;
    nurbs_ctrl_.assign(1, pos_.xyz());
    nurbs_weights_.assign(1, 1.0);
    nurbs_order_ = 3;
    if (w.has('l')) {
      const double l = w['l'].value;
      if (l != std::floor(l) || l < 2 || l > kMaxNurbsOrder) {
        fail(w['l'].col,
             fmt::format("NURBS order L must be an integer from 2 to {}", kMaxNurbsOrder));
      }
      nurbs_order_ = static_cast<int>(l);
    }
  } else if (w.has('l')) {
    fail(w['l'].col, "L word (the NURBS order) only on the G5.2 line that opens the block");
  } else if (!nurbs_open_) {
    // (G5.2 carried over in the modal state of a controller's next MDI line: the points are not.)
    if (have_axes) fail(w.first_col, "NURBS control point without an open G5.2 block");
    return;
  }
  const double weight = w.has('p') ? w['p'].value : 1.0;
  if (w.has('p') && !(weight > 0)) fail(w['p'].col, "NURBS weight P must be positive");
  if (!have_axes) {
    if (opens && w.has('p')) nurbs_weights_[0] = weight;
    return;
  }
  if (nurbs_ctrl_.size() >= kMaxNurbsPoints) {
    fail(w.first_col,
         fmt::format("a NURBS block holds at most {} control points", kMaxNurbsPoints));
  }
  // Words left out (and G91 increments) are taken from the last control point.
  const AxisVec here = pos_;
  pos_[kX] = nurbs_ctrl_.back().x;
  pos_[kY] = nurbs_ctrl_.back().y;
  const AxisVec p = target_from_words(false);
  pos_ = here;
  nurbs_ctrl_.push_back({p[kX], p[kY], here[kZ]});
  nurbs_weights_.push_back(weight);
}

void Interpreter::Impl::nurbs_end(std::uint32_t col) {
  nurbs_open_ = false;
  const auto order = static_cast<std::size_t>(nurbs_order_);
  if (nurbs_ctrl_.size() < order) {
    fail(col, fmt::format("a NURBS of order {} needs at least {} control points, the start "
                          "included ({} given)",
                          order, order, nurbs_ctrl_.size()));
  }
  move_feed_mm_min(0, col);
  AxisVec target = pos_;
  target[kX] = nurbs_ctrl_.back().x;
  target[kY] = nurbs_ctrl_.back().y;
  emit_spline(PlaneSpline::nurbs(nurbs_ctrl_, nurbs_weights_, nurbs_order_), target, col);
}

// The curve from pos_ to `target` as arc (and, where none fits, line) blocks at the feed, the
// last one ending exactly on the target.
void Interpreter::Impl::emit_spline(const PlaneSpline& curve, const AxisVec& target,
                                    std::uint32_t col) {
  const SplineFit fit = fit_arcs(curve, spline_tolerance_mm());
  AxisVec lo = pos_, hi = pos_;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    lo[a] = std::min(pos_[a], target[a]);
    hi[a] = std::max(pos_[a], target[a]);
  }
  lo[kX] = std::min(lo[kX], fit.lo.x);
  lo[kY] = std::min(lo[kY], fit.lo.y);
  hi[kX] = std::max(hi[kX], fit.hi.x);
  hi[kY] = std::max(hi[kY], fit.hi.y);
  check_travel(lo, hi, target, col);
  move_feed_mm_min_ = move_feed_mm_min(fit.length_mm, col);
  const PathMode last_mode = block_path_mode();
  // Inside the curve the joints are tangent: no stop even in G61.1.
  const PathMode inner =
      modal_.path_mode == PathMode::kExactStop ? PathMode::kExactPath : modal_.path_mode;
  for (std::size_t i = 0; i < fit.pieces.size(); ++i) {
    const SplinePiece& piece = fit.pieces[i];
    const bool last = i + 1 == fit.pieces.size();
    Block b = base_block(piece.arc ? BlockKind::kArc : BlockKind::kLine);
    b.col = col;
    b.end = pos_;
    b.end[kX] = piece.end.x;
    b.end[kY] = piece.end.y;
    if (last) b.end = target;
    b.feed_mm_min = move_feed_mm_min_;
    b.path_mode = last ? last_mode : inner;
    b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
    b.smooth_tolerance_mm = modal_.smooth_tolerance_mm;
    if (piece.arc) {
      b.center = {piece.center.x, piece.center.y, pos_[kZ]};
      b.normal = {0, 0, piece.normal.z > 0 ? 1.0 : -1.0};  // the XY plane's, exactly
    }
    out_.push_back(b);
    pos_ = b.end;
  }
  pos_ = target;
}

}  // namespace cncore::interp
