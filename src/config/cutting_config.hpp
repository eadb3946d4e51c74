// Cutting-simulation settings: the stock box, the tool table, the material and the
// spindle. Part of the machine configuration ([stock], [[tools]], [cutting]); the simulation is
// active when the configuration has a [stock] section.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cncore {

enum class ToolShape : std::uint8_t {
  kFlat,      // flat end mill: flat bottom of radius D/2
  kBall,      // ball end mill: hemisphere of radius D/2
  kBullNose,  // flat centre of radius D/2 − r with a torus corner of radius r
};

struct ToolSpec {
  std::uint32_t number = 1;  // T word
  ToolShape shape = ToolShape::kFlat;
  double diameter_mm = 10;
  double corner_radius_mm = 0;  // bull nose only; a ball's is D/2, a flat end mill's 0
  std::uint32_t flutes = 2;
  double length_mm = 0;  // tool length offset (G43 applies it along Z)

  double radius_mm() const { return diameter_mm / 2; }
  // The corner radius the shape implies: 0 (flat), D/2 (ball), corner_radius_mm (bull nose).
  double effective_corner_mm() const {
    return shape == ToolShape::kFlat
               ? 0
               : (shape == ToolShape::kBall ? diameter_mm / 2 : corner_radius_mm);
  }

  friend bool operator==(const ToolSpec&, const ToolSpec&) = default;
};

// Specific cutting energy kc of a named material, N/mm² (1 N/mm² = 1 mJ/mm³: power in W =
// kc · MRR[mm³/s] / 1000).
struct Material {
  const char* name;
  double kc_n_mm2;
  const char* note;
};
// The built-in material table (typical mid-range values; see docs/cutting-simulation.md).
const std::vector<Material>& material_table();
// kc of a named material, or < 0 when the name is unknown.
double material_kc_n_mm2(const std::string& name);

struct StockConfig {
  bool enabled = false;                   // a [stock] section is present
  std::array<double, 3> min_mm{0, 0, 0};  // lowest corner (X, Y, Z), machine coordinates
  std::array<double, 3> size_mm{0, 0, 0};
  double cell_mm = 0.1;         // height-map cell edge
  double max_memory_mb = 1024;  // cap on the height map: cells × 4 bytes

  friend bool operator==(const StockConfig&, const StockConfig&) = default;
};

struct CuttingConfig {
  StockConfig stock;
  std::vector<ToolSpec> tools;  // [[tools]], numbers unique
  std::string material = "aluminium_6061";
  double kc_n_mm2 = 0;             // > 0 overrides the material's value
  double spindle_power_kw = 5.5;   // rated spindle power: load 100 % = this power
  std::uint32_t default_tool = 0;  // tool in the spindle before the first M6; 0 = first listed
  double load_window_s = 0.02;     // MRR is averaged over this window (a spindle-load meter)

  // kc in force: kc_n_mm2 when set, else the material's.
  double effective_kc_n_mm2() const {
    return kc_n_mm2 > 0 ? kc_n_mm2 : material_kc_n_mm2(material);
  }
  const ToolSpec* find_tool(std::uint32_t number) const {
    for (const ToolSpec& t : tools) {
      if (t.number == number) return &t;
    }
    return nullptr;
  }

  friend bool operator==(const CuttingConfig&, const CuttingConfig&) = default;
};

// The [stock], [[tools]] and [cutting] sections as TOML (empty-ish with a commented example
// when no stock is configured). Parsing the text gives back the same settings.
std::string cutting_config_to_toml(const CuttingConfig& config);

}  // namespace cncore
