// The cutting simulation: the stock height map lowered by the tool every interpolation
// cycle, the material-removal rate and the spindle load that follows from it. It observes the
// samples of a run (the tool position, T / M6 events) and is a spindle-load source for adaptive
// feed control (spec 04).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "feedcontrol/load_source.hpp"
#include "simulation/cutting/heightmap.hpp"
#include "simulation/run.hpp"

namespace cncore::cut {

struct CuttingStats {
  double removed_mm3 = 0;            // total volume removed
  double peak_mrr_mm3_s = 0;         // highest windowed MRR
  double peak_load_pct = 0;          // highest load
  double load_sum_pct = 0;           // Σ load over the cycles with load > 0
  std::uint64_t cutting_cycles = 0;  // cycles with load > 0
  std::uint64_t cycles = 0;
  std::uint32_t tool_changes = 0;
  // Mean load over every cycle of the run (air time included), %.
  double mean_load_pct() const {
    return cycles > 0 ? load_sum_pct / static_cast<double>(cycles) : 0;
  }
  // Mean load while cutting (cycles with load > 0), %.
  double mean_cutting_load_pct() const {
    return cutting_cycles > 0 ? load_sum_pct / static_cast<double>(cutting_cycles) : 0;
  }
};

class CuttingSimulator final : public sim::SampleObserver, public feed::LoadSource {
 public:
  // machine.cutting must have a stock (stock.enabled) and a tool table. program_path names the
  // program in errors (a T word whose tool is not in the table).
  CuttingSimulator(const MachineConfig& machine, std::string program_path);

  // Checks every T word against the tool table: InputError(program, line, col) otherwise.
  void on_block(const Block& block) override;
  // Sweeps the tool from the previous sample's position to this one and updates the load.
  void on_sample(const motion::Sample& sample) override;
  // Same, and writes the load into sample.load_pct.
  void process(motion::Sample& sample) noexcept;

  // LoadSource: the load after the last sample observed (the position comes from on_sample /
  // process, which must run before the adaptive loop asks for this cycle's load).
  double load_pct(double t_s, double path_s_mm, double feed_mm_min) noexcept override;

  double last_load_pct() const { return load_pct_; }
  double last_mrr_mm3_s() const { return mrr_mm3_s_; }
  double last_cycle_removed_mm3() const { return last_removed_mm3_; }
  const CuttingStats& stats() const { return stats_; }
  const HeightMap& map() const { return map_; }
  HeightMap& map() { return map_; }
  const ToolSpec& tool() const { return tool_; }
  double kc_n_mm2() const { return kc_n_mm2_; }
  double period_s() const { return period_s_; }

  // load % = 100 · P / P_rated, P = kc · MRR (N/mm² · mm³/s = mW … so W = kc·MRR/1000).
  static double load_from_mrr(double mrr_mm3_s, double kc_n_mm2, double power_kw) {
    return 100.0 * kc_n_mm2 * mrr_mm3_s / 1000.0 / (power_kw * 1000.0);
  }

 private:
  void select_tool(std::uint32_t number) noexcept;

  const CuttingConfig* config_;
  std::string program_;
  HeightMap map_;
  ToolSpec tool_;
  ToolProfile profile_;
  std::uint32_t selected_ = 0;  // T word seen, made current by M6
  double kc_n_mm2_;
  double period_s_;
  bool have_position_ = false;
  Vec3 last_{};
  // MRR over a moving window of the last window_.size() cycles (a load meter's averaging).
  std::vector<double> window_;
  std::size_t window_next_ = 0;
  double window_sum_ = 0;
  double last_removed_mm3_ = 0;
  double mrr_mm3_s_ = 0;
  double load_pct_ = 0;
  CuttingStats stats_;
};

// Sends every sample through the simulator (which writes Sample::load_pct) and then on to the
// downstream observers, so the trajectory and the summary see the load.
class CuttingStage final : public sim::SampleObserver {
 public:
  CuttingStage(CuttingSimulator& sim, std::vector<sim::SampleObserver*> downstream)
      : sim_(&sim), downstream_(std::move(downstream)) {}
  void on_block(const Block& block) override;
  void on_sample(const motion::Sample& sample) override;
  void on_finish() override;

 private:
  CuttingSimulator* sim_;
  std::vector<sim::SampleObserver*> downstream_;
};

// The summary JSON (io::summary_to_json's text) with a "cutting" object added: removed volume,
// peak MRR, peak and mean load (over the run and while cutting), material, kc, spindle power.
std::string summary_json_with_cutting(const std::string& summary_json, const CuttingSimulator& sim,
                                      const CuttingConfig& config);
// Lines for the human summary (each ends with a newline).
std::string format_cutting_summary(const CuttingSimulator& sim, const CuttingConfig& config);

// Outputs of the final map. PNG: a top view (north = +Y up), colour by height from the stock
// bottom (dark blue) to the top (light), with hill shading from the north-west. Grid: CSV
// (comment header with the geometry, then one row per Y from the lowest, heights in mm) or,
// for any other extension, binary: "CNCZMAP1", uint32 nx, ny, float64 x0, y0, cell (mm),
// then nx·ny float32 heights row by row (little-endian).
std::string heightmap_png(const HeightMap& map);
// The PNG's colour (unshaded, 0–255 each) at the fraction u of the height from the stock bottom
// (0) to the top (1): the scale a page draws beside it.
std::array<unsigned char, 3> heightmap_colour(double u);
std::string heightmap_grid(const HeightMap& map, bool csv);

}  // namespace cncore::cut
