#include "interpreter/expression.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace cncore::interp {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kEqualTolerance = 0.0001;  // LinuxCNC TOLERANCE_EQUAL for EQ / NE
constexpr int kMaxNesting = 64;             // guards the recursion against hostile input

enum class Op {
  kNone,
  kPow,
  kMul,
  kDiv,
  kMod,
  kAdd,
  kSub,
  kEq,
  kNe,
  kGt,
  kGe,
  kLt,
  kLe,
  kAnd,
  kOr,
  kXor
};

int level_of(Op op) {
  switch (op) {
    case Op::kPow:
      return 4;
    case Op::kMul:
    case Op::kDiv:
    case Op::kMod:
      return 3;
    case Op::kAdd:
    case Op::kSub:
      return 2;
    case Op::kEq:
    case Op::kNe:
    case Op::kGt:
    case Op::kGe:
    case Op::kLt:
    case Op::kLe:
      return 1;
    case Op::kAnd:
    case Op::kOr:
    case Op::kXor:
      return 0;
    case Op::kNone:
      break;
  }
  return -1;
}

bool starts(const std::string& t, std::size_t pos, std::string_view word) {
  return t.compare(pos, word.size(), word) == 0;
}

// Reads the binary operator at t[pos] without consuming it; sets its length.
Op peek_op(const std::string& t, std::size_t pos, std::size_t& len) {
  if (pos >= t.size()) return Op::kNone;
  len = 1;
  switch (t[pos]) {
    case '*':
      if (pos + 1 < t.size() && t[pos + 1] == '*') {
        len = 2;
        return Op::kPow;
      }
      return Op::kMul;
    case '/':
      return Op::kDiv;
    case '+':
      return Op::kAdd;
    case '-':
      return Op::kSub;
    default:
      break;
  }
  // Word operators, dispatched on their first letter (this runs for every operand).
  auto word = [&](std::string_view w, Op op) {
    if (!starts(t, pos, w)) return Op::kNone;
    len = w.size();
    return op;
  };
  switch (t[pos]) {
    case 'm':
      return word("mod", Op::kMod);
    case 'e':
      return word("eq", Op::kEq);
    case 'n':
      return word("ne", Op::kNe);
    case 'g':
      return word("gt", Op::kGt) != Op::kNone ? Op::kGt : word("ge", Op::kGe);
    case 'l':
      return word("lt", Op::kLt) != Op::kNone ? Op::kLt : word("le", Op::kLe);
    case 'a':
      return word("and", Op::kAnd);
    case 'o':
      return word("or", Op::kOr);
    case 'x':
      return word("xor", Op::kXor);
    default:
      break;
  }
  return Op::kNone;
}

}  // namespace

double Evaluator::real_value(std::size_t& pos) {
  const std::size_t start = pos;
  const double v = raw_value(pos);
  // inf and NaN (EXP[1000], [EXP[1000] - EXP[1000]]) would slip past every later check.
  if (!std::isfinite(v)) fail(start, "value is not a finite number");
  return v;
}

double Evaluator::raw_value(std::size_t& pos) {
  if (pos >= t_.size()) fail(pos, "missing value at the end of the line");
  const char c = t_[pos];
  if (c == '[') return expression(pos);
  if (c == '#') return read(param_ref(pos));
  if (c == '-' || c == '+') {
    // A chain of signs recurses once per sign: bounded like brackets.
    if (++depth_ > kMaxNesting) fail(pos, "too many signs in a row");
    ++pos;
    const double v = real_value(pos);
    --depth_;
    return c == '-' ? -v : v;
  }
  if (is_lower(c)) return unary_function(pos);
  double v = 0;
  if (!scan_number(line_, pos, v, ctx_)) {
    fail(pos, "bad number or value: unexpected '" + printable(c) + "'");
  }
  return v;
}

ParamRef Evaluator::param_ref(std::size_t& pos) {
  ParamRef ref;
  ref.col = line_.col(pos);
  ++pos;  // '#'
  if (pos < t_.size() && t_[pos] == '<') {
    const std::size_t close = t_.find('>', pos);
    if (close == std::string::npos) fail(pos, "named parameter without closing '>'");
    if (close == pos + 1) fail(pos, "empty parameter name '#<>'");
    ref.name = std::string_view(t_).substr(pos + 1, close - pos - 1);
    pos = close + 1;
    return ref;
  }
  const std::size_t at = pos;
  if (++depth_ > kMaxNesting) fail(at, "parameters nested too deeply");
  const double index = real_value(pos);  // a number, [expr] or #n (indirection)
  --depth_;
  const double rounded = std::nearbyint(index);
  if (std::fabs(index - rounded) > 1e-4 || rounded < 1 || rounded > Parameters::kMaxNumbered) {
    ctx_.fail(ref.col,
              "parameter number out of range (1…" + std::to_string(Parameters::kMaxNumbered) + ")");
  }
  ref.number = static_cast<int>(rounded);
  return ref;
}

double Evaluator::read(const ParamRef& ref) const {
  if (ref.number > 0) return params_.numbered(ref.number);
  if (double live = 0; params_.read_live_named(ref.name, live)) return live;
  const double* v = params_.find_named(ref.name);
  if (v == nullptr) {
    ctx_.fail(ref.col, "undefined parameter #<" + printable(ref.name) + ">");
  }
  return *v;
}

double Evaluator::expression(std::size_t& pos) {
  const std::size_t open = pos;
  if (++depth_ > kMaxNesting) fail(open, "expression nested too deeply");
  ++pos;  // '['
  const double v = binary(pos, 0);
  if (pos >= t_.size() || t_[pos] != ']') {
    if (pos >= t_.size()) fail(open, "unclosed '[' in expression");
    fail(pos, "unexpected '" + printable(t_[pos]) + "' in expression");
  }
  ++pos;
  --depth_;
  return v;
}

// Precedence climbing: parse operands joined by operators of level >= `level`, left to right.
double Evaluator::binary(std::size_t& pos, int level) {
  if (level > 4) return operand(pos);
  double lhs = binary(pos, level + 1);
  for (;;) {
    std::size_t len = 0;
    const Op op = peek_op(t_, pos, len);
    if (op == Op::kNone) {
      if (pos < t_.size() && t_[pos] != ']') {
        fail(pos, "unknown operator '" + printable(t_[pos]) + "' in expression");
      }
      return lhs;
    }
    if (level_of(op) != level) return lhs;
    const std::size_t op_pos = pos;
    pos += len;
    const double rhs = binary(pos, level + 1);
    switch (op) {
      case Op::kPow:
        if (lhs < 0 && rhs != std::floor(rhs)) {
          fail(op_pos, "negative number raised to a non-integer power");
        }
        lhs = std::pow(lhs, rhs);
        break;
      case Op::kMul:
        lhs *= rhs;
        break;
      case Op::kDiv:
        if (rhs == 0.0) fail(op_pos, "division by zero");
        lhs /= rhs;
        break;
      case Op::kMod:
        // LinuxCNC: fmod, then shifted into [0, |rhs|).
        if (rhs == 0.0) fail(op_pos, "MOD by zero");
        lhs = std::fmod(lhs, rhs);
        if (lhs < 0) lhs += std::fabs(rhs);
        break;
      case Op::kAdd:
        lhs += rhs;
        break;
      case Op::kSub:
        lhs -= rhs;
        break;
      case Op::kEq:
        lhs = std::fabs(lhs - rhs) < kEqualTolerance ? 1 : 0;
        break;
      case Op::kNe:
        lhs = std::fabs(lhs - rhs) >= kEqualTolerance ? 1 : 0;
        break;
      case Op::kGt:
        lhs = lhs > rhs ? 1 : 0;
        break;
      case Op::kGe:
        lhs = lhs >= rhs ? 1 : 0;
        break;
      case Op::kLt:
        lhs = lhs < rhs ? 1 : 0;
        break;
      case Op::kLe:
        lhs = lhs <= rhs ? 1 : 0;
        break;
      case Op::kAnd:
        lhs = (lhs != 0 && rhs != 0) ? 1 : 0;
        break;
      case Op::kOr:
        lhs = (lhs != 0 || rhs != 0) ? 1 : 0;
        break;
      case Op::kXor:
        lhs = ((lhs != 0) != (rhs != 0)) ? 1 : 0;
        break;
      case Op::kNone:
        break;
    }
  }
}

double Evaluator::operand(std::size_t& pos) {
  if (pos >= t_.size()) fail(pos, "missing operand at the end of the line");
  if (t_[pos] == ']') fail(pos, "missing operand before ']'");
  return real_value(pos);
}

double Evaluator::unary_function(std::size_t& pos) {
  const std::size_t start = pos;
  while (pos < t_.size() && is_lower(t_[pos])) ++pos;
  const std::string_view name = std::string_view(t_).substr(start, pos - start);
  if (pos >= t_.size() || t_[pos] != '[') {
    fail(start, "unknown function or word '" + printable(name) + "'");
  }
  if (name == "exists") {
    // EXISTS[#<name>]: 1 when the named parameter has been set.
    // EXISTS[#n]: 1 when n is a parameter number; 0 when it is out of range (no error).
    const std::size_t open = pos++;
    if (pos >= t_.size() || t_[pos] != '#') fail(pos, "EXISTS needs a parameter");
    double result = 0;
    if (pos + 1 < t_.size() && t_[pos + 1] == '<') {
      const ParamRef ref = param_ref(pos);
      result = params_.find_named(ref.name) != nullptr ? 1 : 0;
    } else {
      ++pos;
      const double index = real_value(pos);
      const double rounded = std::nearbyint(index);
      result =
          std::fabs(index - rounded) <= 1e-4 && rounded >= 1 && rounded <= Parameters::kMaxNumbered
              ? 1
              : 0;
    }
    if (pos >= t_.size() || t_[pos] != ']') fail(open, "unclosed '[' after EXISTS");
    ++pos;
    return result;
  }
  const double arg = expression(pos);
  auto domain = [&](const char* what) { fail(start, std::string(what)); };
  if (name == "atan") {
    // ATAN[y]/[x]: the two-argument arc tangent, in degrees.
    if (pos >= t_.size() || t_[pos] != '/' || pos + 1 >= t_.size() || t_[pos + 1] != '[') {
      fail(pos, "ATAN needs the form ATAN[y]/[x]");
    }
    ++pos;
    const double x = expression(pos);
    return std::atan2(arg, x) * kDegPerRad;
  }
  if (name == "sin") return std::sin(arg / kDegPerRad);
  if (name == "cos") return std::cos(arg / kDegPerRad);
  if (name == "tan") return std::tan(arg / kDegPerRad);
  if (name == "asin") {
    if (arg < -1 || arg > 1) domain("ASIN argument outside [-1, 1]");
    return std::asin(arg) * kDegPerRad;
  }
  if (name == "acos") {
    if (arg < -1 || arg > 1) domain("ACOS argument outside [-1, 1]");
    return std::acos(arg) * kDegPerRad;
  }
  if (name == "sqrt") {
    if (arg < 0) domain("SQRT of a negative number");
    return std::sqrt(arg);
  }
  if (name == "ln") {
    if (arg <= 0) domain("LN of a number that is not positive");
    return std::log(arg);
  }
  if (name == "exp") return std::exp(arg);
  if (name == "abs") return std::fabs(arg);
  if (name == "round") return std::round(arg);
  if (name == "fix") return std::floor(arg);
  if (name == "fup") return std::ceil(arg);
  fail(start, "unknown function '" + printable(name) + "'");
}

}  // namespace cncore::interp
