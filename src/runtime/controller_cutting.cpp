// The control interface's side of the cutting simulation (src/runtime/cutting.hpp).
#include "runtime/controller_impl.hpp"

namespace cncore::runtime {

std::shared_ptr<const HeightMapGrid> Controller::heightmap() const {
  return impl_->cutting ? impl_->cutting->heightmap() : nullptr;
}

Result Controller::reset_stock() {
  if (!impl_->cutting) {
    return Result::fail("the machine has no [stock]: there is no cutting simulation to reset");
  }
  impl_->cutting->request_fresh_stock();
  return {};
}

}  // namespace cncore::runtime
