// What a controller carries from one program or MDI line to the next: the persistent parameters
// the modal state and the tool table.
#include "interpreter/interpreter.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

std::map<int, double> Interpreter::numbered_parameters(int first, int last) const {
  std::map<int, double> out;
  for (int n = first; n <= last; ++n) {
    if (Parameters::valid_number(n)) out[n] = impl_->params_.stored(n);
  }
  return out;
}

ModalState Interpreter::modal_state() const {
  return impl_->modal_;
}

const ToolTable& Interpreter::tool_table() const {
  return impl_->tools_;
}

}  // namespace cncore::interp
