// libFuzzer target: the table reader and planner (spec 02) on arbitrary table text, then the
// first cycles of the run. Tables in one input are separated by a line "====" (several tables
// drive several axes). Bad input must end in InputError; any other exception, a crash, a
// sanitizer report or a non-finite sample is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "tables/table.hpp"

namespace {

// Cycles run per input at most: a valid table may run for hours of machine time (a slow
// input, not a bug); the first 20 000 cycles (20 s at 1 ms) cover the reading of rows.
constexpr std::uint64_t kMaxCycles = 20000;
struct StopRun {};

std::vector<std::string_view> split_tables(std::string_view text) {
  std::vector<std::string_view> parts;
  for (;;) {
    const std::size_t sep = text.find("\n====\n");
    if (sep == std::string_view::npos) break;
    parts.push_back(text.substr(0, sep + 1));
    text.remove_prefix(sep + 6);
  }
  parts.push_back(text);
  return parts;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const cncore::MachineConfig machine = cncore::default_machine_config();
  try {
    std::vector<cncore::tables::Table> tables;
    int n = 0;
    for (std::string_view part : split_tables(text)) {
      tables.push_back(cncore::tables::parse_table(part, "t" + std::to_string(++n) + ".tbl"));
      if (tables.size() > 8) break;
    }
    cncore::tables::RunOptions options;
    options.settings.slow_to_fit = (size & 1) != 0;
    options.settings.cancel_mode =
        (size & 2) != 0 ? cncore::tables::CancelMode::kRebase : cncore::tables::CancelMode::kClear;
    options.values.params = {{1, 10.0}, {2, -5.0}};
    options.values.macros = {{100, 2.5}, {101, -250.0}};
    options.values.signals = {{1001, 1.0}};
    options.values.signal_changes = {{0.05, 1001, 3.0}};
    options.reference = cncore::tables::default_reference(tables.front(), machine, 1000, 1000);
    const cncore::tables::TablePlan plan = cncore::tables::plan_tables(tables, machine, options);
    (void)cncore::tables::format_effective(plan);
    for (const auto& d : plan.diagnostics) (void)d.formatted();
    if (plan.has_errors()) return 0;
    std::uint64_t cycles = 0;
    try {
      cncore::tables::run_tables(plan, [&](const cncore::tables::TableSample& s) {
        for (double x : s.position.v) {
          if (!std::isfinite(x)) std::abort();
        }
        if (!std::isfinite(s.t_s) || !std::isfinite(s.ref)) std::abort();
        if (++cycles >= kMaxCycles) throw StopRun{};
      });
    } catch (const StopRun&) {
    }
  } catch (const cncore::InputError& e) {
    (void)e.formatted();
  }
  return 0;
}
