// Parameters (RS274/NGC "variables"): numbered #1…#5601, named local #<name> (one scope per
// subroutine call) and named global #<_name>. Numbered #1…#30 are the subroutine arguments and
// are local to a call. LinuxCNC's system numbers that cncore maintains (all lengths in mm):
//   #5211…#5216  G92 offset X Y Z A B C        #5210  1 when the G92 offset is applied
//   #5220        active coordinate system (1 = G54 … 9 = G59.3)
//   #5221+20·(n−1)+a  work offset of system n, axis a (X Y Z A B C)
//   #5161…#5166  G28 home, #5181…#5186 G30 home  (machine coordinates)
//   #5400 tool in the spindle, #5420…#5425 current position (program coordinates)
//   #5021…#5026  current position in machine coordinates (without the tool offset)
//   #5230+20·(n−1)  XY rotation of system n (degrees)
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace cncore::interp {

struct StringHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
};
using NamedMap = std::unordered_map<std::string, double, StringHash, std::equal_to<>>;

// Values that are computed rather than stored (current position); supplied by the interpreter.
class LiveParameters {
 public:
  virtual ~LiveParameters() = default;
  virtual bool read_live(int number, double& value) const = 0;
  // Named system parameters (#<_x>, #<_abs_x>…); names are lower case.
  virtual bool read_live_named(std::string_view /*name*/, double& /*value*/) const { return false; }
};

class Parameters {
 public:
  static constexpr int kMaxNumbered = 5601;  // #1 … #5601
  static constexpr int kArgCount = 30;       // #1 … #30: subroutine arguments, local per call

  Parameters();

  void set_live(const LiveParameters* live) { live_ = live; }

  double numbered(int n) const;
  // The stored value, bypassing the live values (for parameters that are never live).
  double stored(int n) const { return numbered_[static_cast<std::size_t>(n)]; }
  void set_numbered(int n, double value) { numbered_[static_cast<std::size_t>(n)] = value; }
  static bool valid_number(int n) { return n >= 1 && n <= kMaxNumbered; }

  // A leading '_' names a global; otherwise the parameter is local to the current call.
  const double* find_named(std::string_view name) const;
  // A computed named parameter (#<_x>…): true and its value, or false.
  bool read_live_named(std::string_view name, double& value) const {
    return live_ != nullptr && name.starts_with('_') && live_->read_live_named(name, value);
  }
  void set_named(std::string_view name, double value);

  // A subroutine call opens a new scope: fresh #1…#30 (the arguments) and fresh named locals.
  void push_scope(const std::array<double, kArgCount>& args);
  void pop_scope();
  std::size_t depth() const { return depth_; }

 private:
  struct Scope {
    std::array<double, kArgCount> saved_args{};  // caller's #1…#30
    NamedMap locals;
  };
  std::vector<double> numbered_;
  NamedMap globals_;
  // scopes_[0] is the main program; scopes_[depth_ - 1] the current call. Scopes above depth_
  // are kept (cleared) for reuse, so calls in a loop do not allocate.
  std::vector<Scope> scopes_;
  std::size_t depth_ = 1;
  const LiveParameters* live_ = nullptr;
};

}  // namespace cncore::interp
