// Values and expressions of RS274/NGC (LinuxCNC): a word value is a number, a parameter
// (#12, #<name>, #<_global>, #[expr], ##n), a bracketed expression [ … ] or a unary function
// (SIN[…], ATAN[y]/[x], EXISTS[#<name>]). Binary operators by precedence, each level
// evaluated left to right:
//   **                      (highest)
//   *  /  MOD
//   +  -
//   EQ NE GT GE LT LE
//   AND OR XOR              (lowest)
// Trigonometry is in degrees. EQ/NE compare with LinuxCNC's tolerance 0.0001.
#pragma once

#include <cstddef>
#include <string_view>

#include "interpreter/lexer.hpp"
#include "interpreter/parameters.hpp"

namespace cncore::interp {

// A reference to a parameter, as written on the left of '='.
struct ParamRef {
  int number = 0;         // > 0 for numbered parameters
  std::string_view name;  // named parameter (view into the normalised line)
  std::uint32_t col = 0;  // column of '#'
};

class Evaluator {
 public:
  Evaluator(const NormLine& line, const ErrorContext& ctx, const Parameters& params)
      : line_(line), t_(line.text), ctx_(ctx), params_(params) {}

  // A word value at t[pos] (after the letter); advances pos.
  double real_value(std::size_t& pos);
  // A parameter reference at t[pos] == '#'; advances pos past it.
  ParamRef param_ref(std::size_t& pos);
  // The value of a parameter reference (error when a named parameter was never set).
  double read(const ParamRef& ref) const;

 private:
  double raw_value(std::size_t& pos);   // real_value without the finiteness check
  double expression(std::size_t& pos);  // t[pos] == '['
  double binary(std::size_t& pos, int level);
  double operand(std::size_t& pos);
  double unary_function(std::size_t& pos);
  [[noreturn]] void fail(std::size_t pos, const std::string& message) const {
    ctx_.fail(line_.col(pos), message);
  }

  const NormLine& line_;
  const std::string& t_;
  const ErrorContext& ctx_;
  const Parameters& params_;
  int depth_ = 0;
};

}  // namespace cncore::interp
