#include "interpreter/parameters.hpp"

namespace cncore::interp {

Parameters::Parameters() : numbered_(kMaxNumbered + 1, 0.0) {
  scopes_.emplace_back();
}

double Parameters::numbered(int n) const {
  double v = 0;
  if (live_ != nullptr && live_->read_live(n, v)) return v;
  return numbered_[static_cast<std::size_t>(n)];
}

const double* Parameters::find_named(std::string_view name) const {
  const NamedMap& map = (!name.empty() && name[0] == '_') ? globals_ : scopes_[depth_ - 1].locals;
  auto it = map.find(name);
  return it == map.end() ? nullptr : &it->second;
}

void Parameters::set_named(std::string_view name, double value) {
  NamedMap& map = (!name.empty() && name[0] == '_') ? globals_ : scopes_[depth_ - 1].locals;
  auto it = map.find(name);
  if (it != map.end()) {
    it->second = value;
  } else {
    map.emplace(std::string(name), value);
  }
}

void Parameters::push_scope(const std::array<double, kArgCount>& args) {
  if (depth_ == scopes_.size()) scopes_.emplace_back();
  Scope& s = scopes_[depth_++];
  s.locals.clear();
  for (int i = 0; i < kArgCount; ++i) {
    s.saved_args[static_cast<std::size_t>(i)] = numbered_[static_cast<std::size_t>(i + 1)];
    numbered_[static_cast<std::size_t>(i + 1)] = args[static_cast<std::size_t>(i)];
  }
}

void Parameters::pop_scope() {
  if (depth_ <= 1) return;
  const Scope& s = scopes_[--depth_];
  for (int i = 0; i < kArgCount; ++i) {
    numbered_[static_cast<std::size_t>(i + 1)] = s.saved_args[static_cast<std::size_t>(i)];
  }
}

}  // namespace cncore::interp
