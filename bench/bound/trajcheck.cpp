// cncore-trajcheck: checks a trajectory CSV (from `cncore run --trajectory`) against its program
// with the independent checker (tests/support/trajectory_checker.hpp).
//   cncore-trajcheck PROGRAM.ngc TRAJ.csv [--machine FILE.toml] [--path-tolerance MM]
//                    [--margin FRACTION] [--override-ramp S] [--joints]
// Prints the summary and the first violations of each property. Exit codes: 0 no violation,
// 1 violations or bad input, 2 usage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "program_blocks.hpp"
#include "trajectory_checker.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Check a trajectory CSV against its part program (spec 01 P1-P4)"};
  std::string program, csv, machine_file;
  double path_tol = -1, margin = -1, ramp = -1;
  bool joints = false;
  app.add_option("program", program, "part program (G-code)")->required();
  app.add_option("trajectory", csv, "trajectory CSV")->required();
  app.add_option("--machine", machine_file, "machine configuration (TOML); built-in if absent");
  app.add_option("--path-tolerance", path_tol,
                 "P1 tolerance, mm (default 0.001, or the contour "
                 "tolerance with the post-interpolation filter)");
  app.add_option("--margin", margin, "relative margin on every limit (default 0.005)");
  app.add_option("--override-ramp", ramp, "allowance after an override decrease, s (default auto)");
  app.add_flag("--joints", joints, "list every joint: angle, allowed and measured speed");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    const cncore::MachineConfig machine = cncore::machine_config_or_default(machine_file);
    cncore::testing::Limits lim = cncore::testing::limits_from_config(machine);
    if (path_tol > 0) lim.path_tolerance_mm = path_tol;
    if (margin >= 0) lim.margin = margin;
    if (ramp >= 0) lim.override_ramp_s = ramp;
    const auto blocks = cncore::testing::read_blocks(program, machine);
    const auto tr = cncore::testing::load_trajectory_csv(csv);
    const auto rep = cncore::testing::check_trajectory(tr, blocks, lim);
    std::printf("%s", rep.summary().c_str());
    if (joints) {
      for (const auto& j : rep.joints)
        std::printf(
            "joint after segment %zu (line %u): %.3f deg, allowed %.4f mm/s, measured %.4f "
            "mm/s%s\n",
            j.segment, j.line, j.angle_deg, j.vg_mm_s, j.speed_mm_s, j.stop ? " (stop)" : "");
    }
    std::printf("%s\n", rep.ok() ? "OK: no violation" : "VIOLATIONS");
    return rep.ok() ? 0 : 1;
  } catch (const cncore::InputError& e) {
    std::fprintf(stderr, "%s\n", e.formatted().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cncore-trajcheck: %s\n", e.what());
    return 1;
  }
}
