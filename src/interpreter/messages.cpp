// Operator messages: "(msg,TEXT)" shows TEXT; "(debug,TEXT)" shows TEXT with each #n and
// #<name> replaced by the parameter's value as LinuxCNC prints it (%f: six decimals; an unknown
// name prints ######). They go to Options::on_message when the line runs.
#include <fmt/format.h>

#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

void Interpreter::Impl::show_message() {
  if (!on_message_) return;
  const std::string& t = line_.message_text;
  if (line_.message == NormLine::Message::kMsg) {
    on_message_(t);
    return;
  }
  std::string out;
  for (std::size_t i = 0; i < t.size();) {
    if (t[i] != '#') {
      out += t[i++];
      continue;
    }
    std::size_t j = i + 1;
    if (j < t.size() && t[j] == '<') {
      const std::size_t close = t.find('>', j);
      if (close == std::string::npos) {
        out += t.substr(i);
        break;
      }
      std::string name;
      for (std::size_t k = j + 1; k < close; ++k) {
        const char c = t[k];
        if (c == ' ' || c == '\t') continue;
        name += (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
      }
      double v = 0;
      if (params_.read_live_named(name, v)) {
        out += fmt::format("{:.6f}", v);
      } else if (const double* p = params_.find_named(name); p != nullptr) {
        out += fmt::format("{:.6f}", *p);
      } else {
        out += "######";
      }
      i = close + 1;
      continue;
    }
    int n = 0;
    while (j < t.size() && t[j] >= '0' && t[j] <= '9' && n <= Parameters::kMaxNumbered) {
      n = n * 10 + (t[j++] - '0');
    }
    if (j == i + 1 || !Parameters::valid_number(n)) {
      out += t.substr(i, j - i);
    } else {
      out += fmt::format("{:.6f}", params_.numbered(n));
    }
    i = j;
  }
  on_message_(out);
}

}  // namespace cncore::interp
