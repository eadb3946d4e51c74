// cncore-bound: the time-optimal lower bound of a part program on a machine (see bound.hpp).
//   cncore-bound PROGRAM.ngc [--machine FILE.toml] [--override PCT] [--json]
// Prints "bound_s=… motion_s=… dwell_s=… length_mm=… segments=… stops=… blocks=… accel_only_s=…"
// (or one JSON object). With a jerk limit in the machine (`[motion] max_jerk_mm_s3`) bound_s is
// the jerk-aware bound (jerk_bound.hpp) and accel_only_s the bound without it (--no-jerk: jerk
// ignored). Exit codes: 0 ok, 1 bad program or machine file (FILE:LINE:COL: error: …), 2 usage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "bound.hpp"
#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Time-optimal lower bound of a part program's cycle time"};
  std::string program, machine_file;
  double override_pct = 100;
  bool json = false;
  std::string per_block_file;
  std::string model_name = "coupled";
  double resultant_mm_s2 = 0;
  bool no_jerk = false;
  app.add_option("program", program, "part program (G-code)")->required();
  app.add_option("--machine", machine_file, "machine configuration (TOML); built-in if absent");
  app.add_option("--override", override_pct, "constant feed override in % (scales F, not Vmax)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("--json", json, "print one JSON object");
  app.add_option("--model", model_name,
                 "coupled (default: the normal acceleration's and each axis's share on arcs, "
                 "per-axis acceleration on lines) or simple (constant Amax, the first bound)")
      ->check(CLI::IsMember({"coupled", "simple"}));
  app.add_option("--resultant-accel", resultant_mm_s2,
                 "also bound the resultant acceleration on arcs (mm/s², coupled model; 0: off, "
                 "as the checker by default)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_flag("--no-jerk", no_jerk,
               "ignore the machine's jerk limit (the acceleration bound; with a jerk limit the "
               "bound also keeps |jerk| <= max_jerk_mm_s3 along the path)");
  app.add_option("--per-block", per_block_file,
                 "write one TSV row per moving segment: line, kind, length, caps, joint speeds, "
                 "time");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    const cncore::MachineConfig machine = cncore::machine_config_or_default(machine_file);
    cncore::testing::Limits lim = cncore::testing::limits_from_config(machine);
    lim.max_resultant_accel_mm_s2 = resultant_mm_s2;
    if (no_jerk) lim.max_jerk_mm_s3 = 0;
    cncore::interp::Interpreter in(program, machine, {});
    cncore::bound::BoundBuilder builder(lim, model_name == "simple"
                                                 ? cncore::bound::Model::kSimple
                                                 : cncore::bound::Model::kCoupled);
    builder.record_segments(!per_block_file.empty());
    cncore::Block b;
    std::size_t blocks = 0;
    while (in.next(b)) {
      if (b.kind == cncore::BlockKind::kLine || b.kind == cncore::BlockKind::kArc) {
        b.feed_mm_min *= override_pct / 100.0;
      }
      if (b.kind != cncore::BlockKind::kAux && b.kind != cncore::BlockKind::kDwell) ++blocks;
      builder.add(b);
    }
    const auto r = builder.finish();
    if (!per_block_file.empty()) {
      std::FILE* f = std::fopen(per_block_file.c_str(), "w");
      if (f == nullptr) {
        std::fprintf(stderr, "cncore-bound: cannot write %s\n", per_block_file.c_str());
        return 1;
      }
      std::fprintf(f,
                   "line\tkind\tlength_mm\tcap_mm_s\tv_in_mm_s\tv_out_mm_s\tjoin_cap_mm_s\ttime_"
                   "s\tx0\ty0\tz0\tx1\ty1\tz1\n");
      for (const auto& st : builder.segment_times()) {
        std::fprintf(f,
                     "%u\t%s\t%.9g\t%.9g\t%.9g\t%.9g\t%.9g\t%.9g\t%.12g\t%.12g\t%.12g\t%.12g\t%."
                     "12g\t%.12g\n",
                     st.line, st.arc ? "arc" : "line", st.length, st.cap_mm_s, st.v_in_mm_s,
                     st.v_out_mm_s, st.join_cap_mm_s, st.time_s, st.start.x, st.start.y, st.start.z,
                     st.end.x, st.end.y, st.end.z);
      }
      std::fclose(f);
    }
    if (json) {
      std::printf(
          "{\"bound_s\": %.9g, \"motion_s\": %.9g, \"dwell_s\": %.9g, \"length_mm\": %.9g, "
          "\"segments\": %zu, \"stops\": %zu, \"blocks\": %zu, \"accel_only_s\": %.9g}\n",
          r.time_s, r.motion_time_s, r.dwell_s, r.length_mm, r.segments, r.stops, blocks,
          r.accel_motion_time_s + r.dwell_s);
    } else {
      std::printf(
          "bound_s=%.9g motion_s=%.9g dwell_s=%.9g length_mm=%.9g segments=%zu stops=%zu "
          "blocks=%zu accel_only_s=%.9g\n",
          r.time_s, r.motion_time_s, r.dwell_s, r.length_mm, r.segments, r.stops, blocks,
          r.accel_motion_time_s + r.dwell_s);
    }
    return 0;
  } catch (const cncore::InputError& e) {
    std::fprintf(stderr, "%s\n", e.formatted().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cncore-bound: internal error: %s\n", e.what());
    return 3;
  }
}
