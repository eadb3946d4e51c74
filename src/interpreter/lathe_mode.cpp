// G7 / G8, lathe diameter and radius mode (LinuxCNC): in G7 every X word of a block is a
// diameter, so the interpreter reads half of it, whatever uses it (moves, G91 increments, G92,
// G10 offsets); a G7 or G8 applies to the X word of its own block. Nothing else changes: I and
// K (arc centres), R and positions (#5420, the canonical listing) stay radii, as LinuxCNC's.
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

void Interpreter::Impl::apply_lathe_mode() {
  if (const auto* g = words_.group(GGroup::kLatheDiameter)) modal_.diameter_mode = g->code10 == 70;
  auto& x = words_.letter[static_cast<std::size_t>('x' - 'a')];
  if (modal_.diameter_mode && x.present) x.value /= 2;
}

}  // namespace cncore::interp
