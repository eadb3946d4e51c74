#include "config/probe_section.hpp"

#include <fmt/format.h>

#include "config/toml_reader.hpp"

namespace cncore::config_detail {

namespace {

// [x_min, y_min, z_min, x_max, y_max, z_max] with each minimum below its maximum.
ProbeBox read_box(const TomlReader& r, const toml::key& key, const toml::node& node,
                  const std::string& name) {
  const auto* a = node.as_array();
  if (a == nullptr || a->size() != 6) {
    r.fail(key.source(),
           fmt::format("{} must be an array of 6 numbers [x_min, y_min, z_min, x_max, y_max, "
                       "z_max]",
                       name));
  }
  ProbeBox b;
  for (std::size_t i = 0; i < 3; ++i) {
    b.min_mm[i] = r.number(key, *a->get(i), name);
    b.max_mm[i] = r.number(key, *a->get(i + 3), name);
    if (b.max_mm[i] <= b.min_mm[i]) {
      r.fail(key.source(), fmt::format("{}: the {} maximum {} must be above its minimum {}", name,
                                       "XYZ"[i], b.max_mm[i], b.min_mm[i]));
    }
  }
  return b;
}

}  // namespace

void read_probe_section(const std::string& file, const toml::table& t, ProbeConfig& p) {
  const TomlReader r(file);
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "probe." + k;
    if (k == "touch_stock") {
      p.touch_stock = r.boolean(key, node, name);
    } else if (k == "boxes") {
      const auto* list = node.as_array();
      if (list == nullptr) r.fail(key.source(), name + " must be an array of boxes");
      p.boxes.clear();
      for (std::size_t i = 0; i < list->size(); ++i) {
        p.boxes.push_back(read_box(r, key, *list->get(i), fmt::format("{}[{}]", name, i)));
      }
    } else {
      r.unknown(key, name, " (keys are touch_stock, boxes)");
    }
  }
}

std::string probe_section_to_toml(const ProbeConfig& p) {
  std::string o = "\n[probe]  # G38.2–G38.5: what the simulated probe touches\n";
  o += fmt::format("{:<36}# {}\n", fmt::format("touch_stock = {}", p.touch_stock),
                   "the [stock] box, when there is one");
  std::string boxes = "boxes = [";
  for (std::size_t i = 0; i < p.boxes.size(); ++i) {
    const ProbeBox& b = p.boxes[i];
    boxes += fmt::format("{}[{}, {}, {}, {}, {}, {}]", i > 0 ? ", " : "", b.min_mm[0], b.min_mm[1],
                         b.min_mm[2], b.max_mm[0], b.max_mm[1], b.max_mm[2]);
  }
  boxes += "]";
  o += fmt::format("{:<36}# {}\n", boxes,
                   "more solids: [x_min, y_min, z_min, x_max, y_max, z_max], machine mm");
  return o;
}

}  // namespace cncore::config_detail
