#include "config/cutting_config.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "config/cutting_config_toml.hpp"
#include "config/toml_reader.hpp"
#include "core/error.hpp"

namespace cncore {

// Specific cutting energy, N/mm² (= mJ/mm³). Kalpakjian & Schmid, "Manufacturing Engineering
// and Technology", table "Approximate specific-energy requirements in cutting operations", gives
// W·s/mm³ (×1000 = N/mm²): aluminium alloys 0.4–1.1, copper alloys 1.4–3.3, steels 2.7–9.3,
// stainless steels 3.0–5.2. Sandvik Coromant's kc1 (chip thickness 1 mm) is lower: about 700 for
// wrought aluminium, 1500–1800 for medium-carbon steel, 2000–2300 for austenitic stainless; at
// the thin chips of milling (0.05–0.2 mm) kc = kc1·h^−mc rises by 1.5–2×. We take values inside
// both ranges; the feed (chip-thickness) dependence is ignored.
const std::vector<Material>& material_table() {
  static const std::vector<Material> table{
      {"aluminium_6061", 700, "wrought aluminium alloy (range 400-1100)"},
      {"brass_360", 1400, "free-cutting brass, low end of copper alloys (1400-3300)"},
      {"steel_1045", 2700, "medium-carbon steel (2700-9300; kc1 about 1700)"},
      {"stainless_304", 3500, "austenitic stainless steel (3000-5200; kc1 about 2100)"},
  };
  return table;
}

double material_kc_n_mm2(const std::string& name) {
  for (const Material& m : material_table()) {
    if (name == m.name) return m.kc_n_mm2;
  }
  return -1;
}

namespace {

std::string material_names() {
  std::string s;
  for (const Material& m : material_table()) s += (s.empty() ? "" : ", ") + std::string(m.name);
  return s;
}

using CutReader = config_detail::TomlReader;

// The list of keys a section accepts, for the "unknown key" error.
std::string keys_here(const char* keys) {
  return fmt::format(" (keys here: {})", keys);
}

void read_stock(const CutReader& r, const toml::key& section, const toml::table& t,
                StockConfig& s) {
  s.enabled = true;
  toml::source_region size_at = section.source(), cell_at = section.source(),
                      cap_at = section.source();
  bool cap_given = false;
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "stock." + k;
    if (k == "min_mm") {
      s.min_mm = r.triple(key, node, name);
    } else if (k == "size_mm") {
      s.size_mm = r.triple(key, node, name);
      size_at = key.source();
      for (std::size_t i = 0; i < 3; ++i) {
        if (s.size_mm[i] <= 0) {
          r.fail(key.source(),
                 fmt::format("{}: the {} size is {} mm; the stock box needs sizes > 0", name,
                             "xyz"[i], s.size_mm[i]));
        }
      }
    } else if (k == "cell_mm") {
      s.cell_mm = r.positive(key, node, name, "mm");
      cell_at = key.source();
    } else if (k == "max_memory_mb") {
      s.max_memory_mb = r.positive(key, node, name, "MB");
      cap_at = key.source();
      cap_given = true;
    } else {
      r.unknown(key, name, keys_here("min_mm, size_mm, cell_mm, max_memory_mb"));
    }
  }
  if (s.size_mm[0] <= 0 || s.size_mm[1] <= 0 || s.size_mm[2] <= 0) {
    r.fail(size_at, "stock.size_mm is required: the stock box sizes [x, y, z] in mm, all > 0");
  }
  // The height map holds one float per cell.
  const double nx = std::ceil(s.size_mm[0] / s.cell_mm - 1e-9);
  const double ny = std::ceil(s.size_mm[1] / s.cell_mm - 1e-9);
  const double mb = nx * ny * 4 / (1024.0 * 1024.0);
  if (mb > s.max_memory_mb || nx * ny > 4e9) {
    r.fail(cap_given ? cap_at : cell_at,
           fmt::format("the stock height map needs {:.0f} x {:.0f} cells x 4 bytes = {:.1f} MB, "
                       "more than stock.max_memory_mb = {}; raise stock.max_memory_mb or "
                       "stock.cell_mm",
                       nx, ny, mb, s.max_memory_mb));
  }
}

ToolSpec read_tool(const CutReader& r, const toml::source_region& at, const toml::table& t,
                   std::size_t index) {
  ToolSpec tool;
  bool have_number = false, have_diameter = false, have_corner = false;
  toml::source_region corner_at = at;
  const std::string prefix = fmt::format("tools[{}].", index);
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = prefix + k;
    if (k == "number") {
      tool.number = r.count(key, node, name, 0, 1000000000);
      have_number = true;
    } else if (k == "type") {
      const std::string v = r.text(key, node, name);
      if (v == "flat") {
        tool.shape = ToolShape::kFlat;
      } else if (v == "ball") {
        tool.shape = ToolShape::kBall;
      } else if (v == "bull" || v == "bull_nose") {
        tool.shape = ToolShape::kBullNose;
      } else {
        r.fail(key.source(),
               fmt::format(R"({} = "{}": it must be "flat", "ball" or "bull")", name, v));
      }
    } else if (k == "diameter_mm") {
      tool.diameter_mm = r.positive(key, node, name, "mm");
      have_diameter = true;
    } else if (k == "corner_radius_mm") {
      tool.corner_radius_mm = r.number(key, node, name);
      if (tool.corner_radius_mm < 0) r.fail(key.source(), name + " must be >= 0 mm");
      have_corner = true;
      corner_at = key.source();
    } else if (k == "flutes") {
      tool.flutes = r.count(key, node, name, 1, 100);
    } else if (k == "length_mm") {
      tool.length_mm = r.number(key, node, name);
    } else {
      r.unknown(key, name,
                keys_here("number, type, diameter_mm, corner_radius_mm, flutes, length_mm"));
    }
  }
  if (!have_number) r.fail(at, prefix + "number is required (the T word that selects the tool)");
  if (!have_diameter) r.fail(at, prefix + "diameter_mm is required");
  if (tool.shape == ToolShape::kBullNose) {
    if (!have_corner || tool.corner_radius_mm <= 0 ||
        tool.corner_radius_mm > tool.diameter_mm / 2) {
      r.fail(corner_at, fmt::format("{}corner_radius_mm must be > 0 and <= diameter_mm / 2 = {} "
                                    "for a bull-nose tool",
                                    prefix, tool.diameter_mm / 2));
    }
  } else if (have_corner && tool.corner_radius_mm != tool.effective_corner_mm()) {
    r.fail(corner_at,
           fmt::format("{}corner_radius_mm = {} does not fit a {} end mill (it is {})", prefix,
                       tool.corner_radius_mm, tool.shape == ToolShape::kFlat ? "flat" : "ball",
                       tool.effective_corner_mm()));
  }
  if (tool.shape != ToolShape::kBullNose) tool.corner_radius_mm = tool.effective_corner_mm();
  return tool;
}

}  // namespace

bool read_cutting_section(const std::string& file, const toml::key& key, const toml::node& node,
                          CuttingConfig& c, CuttingSources& where) {
  const CutReader r(file);
  const std::string k(key.str());
  if (k == "stock") {
    const auto* t = node.as_table();
    if (t == nullptr) r.fail(key.source(), "stock must be a table");
    where.stock = key.source();
    read_stock(r, key, *t, c.stock);
    return true;
  }
  if (k == "tools") {
    const auto* a = node.as_array();
    if (a == nullptr) r.fail(key.source(), "tools must be an array of tables: [[tools]]");
    c.tools.clear();
    for (std::size_t i = 0; i < a->size(); ++i) {
      const auto* t = a->get(i)->as_table();
      if (t == nullptr) r.fail(key.source(), "tools must be an array of tables: [[tools]]");
      const toml::source_region at = t->source().begin.line > 0 ? t->source() : key.source();
      const ToolSpec tool = read_tool(r, at, *t, i);
      if (c.find_tool(tool.number) != nullptr) {
        r.fail(at, fmt::format("tools[{}]: tool number {} is listed twice", i, tool.number));
      }
      c.tools.push_back(tool);
    }
    return true;
  }
  if (k == "cutting") {
    const auto* t = node.as_table();
    if (t == nullptr) r.fail(key.source(), "cutting must be a table");
    for (const auto& [ck, cn] : *t) {
      const std::string kk(ck.str());
      const std::string name = "cutting." + kk;
      if (kk == "material") {
        c.material = r.text(ck, cn, name);
        where.material = ck.source();
      } else if (kk == "kc_n_mm2") {
        c.kc_n_mm2 = r.number(ck, cn, name);  // 0: the material's value
        if (c.kc_n_mm2 < 0) r.fail(ck.source(), name + " must be >= 0 N/mm² (0 = the material's)");
      } else if (kk == "spindle_power_kw") {
        c.spindle_power_kw = r.positive(ck, cn, name, "kW");
      } else if (kk == "default_tool") {
        c.default_tool = r.count(ck, cn, name, 0, 1000000000);
        where.default_tool = ck.source();
      } else if (kk == "load_window_s") {
        c.load_window_s = r.positive(ck, cn, name, "s");
        if (c.load_window_s > 10) r.fail(ck.source(), name + " must be <= 10 s");
      } else {
        r.unknown(ck, name,
                  keys_here("material, kc_n_mm2, spindle_power_kw, default_tool, load_window_s"));
      }
    }
    return true;
  }
  return false;
}

void validate_cutting_config(const std::string& file, const CuttingConfig& c,
                             const CuttingSources& where) {
  const CutReader r(file);
  if (c.kc_n_mm2 <= 0 && material_kc_n_mm2(c.material) < 0) {
    r.fail(where.material, fmt::format("cutting.material = \"{}\" is not in the material table "
                                       "({}); give cutting.kc_n_mm2 instead",
                                       c.material, material_names()));
  }
  if (c.default_tool != 0 && c.find_tool(c.default_tool) == nullptr) {
    r.fail(where.default_tool,
           fmt::format("cutting.default_tool = {} is not in the tool table ([[tools]])",
                       c.default_tool));
  }
  if (c.stock.enabled && c.tools.empty()) {
    r.fail(where.stock, "[stock] needs a tool table: add at least one [[tools]] entry");
  }
}

std::string cutting_config_to_toml(const CuttingConfig& c) {
  std::string o;
  auto line = [&o](const std::string& key_value, const std::string& comment) {
    o += fmt::format("{:<34} # {}\n", key_value, comment);
  };
  auto num = [](double v) { return fmt::format("{}", v); };
  auto triple = [&num](const std::array<double, 3>& v) {
    // (fmt, not "[" + std::string: GCC 12 -O3 warns a false -Wrestrict on that operator+.)
    return fmt::format("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]));
  };
  const bool any = c.stock.enabled || !c.tools.empty() || c != CuttingConfig{};
  if (!any) {
    o += "\n# Cutting simulation (docs/cutting-simulation.md): a [stock] section turns it on.\n"
         "# [stock]\n"
         "# min_mm = [-50, -50, -20]          # lowest corner of the stock box, mm\n"
         "# size_mm = [100, 100, 20]          # box sizes x, y, z, mm (> 0)\n"
         "# cell_mm = 0.1                     # height-map cell, mm\n"
         "# max_memory_mb = 1024              # cap: cells x 4 bytes\n"
         "# [cutting]\n"
         "# material = \"aluminium_6061\"       # aluminium_6061, brass_360, steel_1045, "
         "stainless_304\n"
         "# spindle_power_kw = 5.5            # rated power: load 100 %\n"
         "# [[tools]]\n"
         "# number = 1                        # T word\n"
         "# type = \"flat\"                     # flat, ball or bull\n"
         "# diameter_mm = 10\n"
         "# corner_radius_mm = 0              # bull nose only\n"
         "# flutes = 2\n";
    return o;
  }
  if (c.stock.enabled) {
    o += "\n[stock]\n";
    line("min_mm = " + triple(c.stock.min_mm), "lowest corner of the stock box, mm");
    line("size_mm = " + triple(c.stock.size_mm), "box sizes x, y, z, mm (> 0)");
    line("cell_mm = " + num(c.stock.cell_mm), "height-map cell edge, mm");
    line("max_memory_mb = " + num(c.stock.max_memory_mb), "cap on the height map (cells x 4 B)");
  }
  o += "\n[cutting]\n";
  line("material = \"" + c.material + "\"", "material table: " + material_names());
  line("kc_n_mm2 = " + num(c.kc_n_mm2), "specific cutting energy, N/mm²; 0 = the material's");
  line("spindle_power_kw = " + num(c.spindle_power_kw), "rated spindle power (load 100 %)");
  line("default_tool = " + std::to_string(c.default_tool),
       "tool before the first M6; 0 = the first listed");
  line("load_window_s = " + num(c.load_window_s), "MRR averaging window, s");
  for (const ToolSpec& t : c.tools) {
    o += "\n[[tools]]\n";
    line("number = " + std::to_string(t.number), "T word");
    line(std::string("type = \"") +
             (t.shape == ToolShape::kFlat   ? "flat"
              : t.shape == ToolShape::kBall ? "ball"
                                            : "bull") +
             "\"",
         "flat, ball or bull");
    line("diameter_mm = " + num(t.diameter_mm), "mm");
    line("corner_radius_mm = " + num(t.corner_radius_mm), "mm (bull nose; ball = D/2, flat = 0)");
    line("flutes = " + std::to_string(t.flutes), "number of flutes");
    line("length_mm = " + num(t.length_mm), "tool length offset, mm (G43)");
  }
  return o;
}

}  // namespace cncore
