// cncore-gen: writes generated part programs (see tests/support/program_gen.hpp).
//   cncore-gen zigzag --strokes 200 --length 5 [--pitch 1] [--feed 10000] [-o FILE]
//   cncore-gen circle --chords 360 --radius 50
//   cncore-gen raster --width 100 --height 60 --stepover 1 --spacing 0.5
//   cncore-gen random --seed 1 --segments 2000 [--min-len 0.2 --max-len 2 --max-turn 90 --refine
//   100] cncore-gen cam --lines 1000000 [--seed 1]
// Without -o the program goes to stdout. Exit codes: 0 ok, 1 cannot write, 2 usage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "program_gen.hpp"

#ifdef CNCORE_GEN_HAS_INTERPRETER
#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#endif

namespace gen = cncore::testing::gen;

int main(int argc, char** argv) {
  CLI::App app{"Generate test part programs (G-code) for cncore"};
  app.require_subcommand(1);
  app.fallthrough();  // -o and --feed may come after the subcommand
  std::string out_file;
  app.add_option("-o,--output", out_file, "output file (default: stdout)");
  double feed = 10000;
  app.add_option("--feed", feed, "programmed feed, mm/min");

  int strokes = 100;
  double length = 5, pitch = 1;
  auto* zz = app.add_subcommand("zigzag", "N strokes of length L along X, pitch P in Y");
  zz->add_option("--strokes", strokes)->check(CLI::Range(1, 100000000));
  zz->add_option("--length", length)->check(CLI::Range(1e-6, 590.0));
  zz->add_option("--pitch", pitch)->check(CLI::Range(1e-6, 100.0));

  int chords = 360;
  double radius = 50;
  auto* ci = app.add_subcommand("circle", "full circle of N chords");
  ci->add_option("--chords", chords)->check(CLI::Range(3, 100000000));
  ci->add_option("--radius", radius)->check(CLI::Range(1e-3, 190.0));

  double width = 100, height = 60, stepover = 1, spacing = 0.5;
  auto* ra = app.add_subcommand("raster", "3-D raster of a smooth surface");
  ra->add_option("--width", width)->check(CLI::Range(1e-3, 590.0));
  ra->add_option("--height", height)->check(CLI::Range(0.0, 390.0));
  ra->add_option("--stepover", stepover)->check(CLI::Range(1e-3, 100.0));
  ra->add_option("--spacing", spacing)->check(CLI::Range(1e-4, 100.0));

  unsigned long long seed = 1;
  int segments = 2000, refine = 1;
  double min_len = 0.2, max_len = 2, max_turn = 90;
  auto* rn = app.add_subcommand("random", "seeded random path of short segments");
  rn->add_option("--seed", seed);
  rn->add_option("--segments", segments)->check(CLI::Range(1, 100000000));
  rn->add_option("--min-len", min_len)->check(CLI::Range(1e-5, 50.0));
  rn->add_option("--max-len", max_len)->check(CLI::Range(1e-5, 50.0));
  rn->add_option("--max-turn", max_turn)->check(CLI::Range(0.0, 180.0));
  rn->add_option("--refine", refine, "cut every segment into k pieces")
      ->check(CLI::Range(1, 100000));

  std::size_t lines = 1000000;
  auto* cam = app.add_subcommand("cam", "CAM-like finishing program of about N lines");
  cam->add_option("--lines", lines)->check(CLI::Range(std::size_t{20}, std::size_t{1000000000}));
  cam->add_option("--seed", seed);

#ifdef CNCORE_GEN_HAS_INTERPRETER
  std::string program, machine_file;
  int factor = 10;
  auto* rf =
      app.add_subcommand("refine", "the same path as PROGRAM, every block cut into k pieces");
  rf->add_option("program", program, "part program (G-code)")->required();
  rf->add_option("--factor", factor, "pieces per block")->check(CLI::Range(1, 100000));
  rf->add_option("--machine", machine_file, "machine configuration (TOML)");
#endif

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (min_len > max_len) {
    std::fprintf(stderr, "cncore-gen: --min-len must not exceed --max-len\n");
    return 2;
  }

  std::ofstream file;
  if (!out_file.empty()) {
    file.open(out_file, std::ios::binary | std::ios::trunc);
    if (!file) {
      std::fprintf(stderr, "cncore-gen: cannot write %s\n", out_file.c_str());
      return 1;
    }
  }
  std::ostream& out = out_file.empty() ? std::cout : file;
  if (*zz) out << gen::zigzag(strokes, length, pitch, feed);
  if (*ci) out << gen::circle_chords(chords, radius, feed);
  if (*ra) out << gen::raster_3d(width, height, stepover, spacing, feed);
  if (*rn) out << gen::random_path(seed, segments, min_len, max_len, max_turn, refine, feed);
  if (*cam) gen::cam_like(out, lines, seed);
#ifdef CNCORE_GEN_HAS_INTERPRETER
  if (*rf) {
    try {
      const cncore::MachineConfig machine = cncore::machine_config_or_default(machine_file);
      cncore::interp::Interpreter in(program, machine, {});
      gen::GcodeWriter w(out, factor);
      cncore::Block b;
      while (in.next(b)) w.add(b);
      w.finish();
    } catch (const cncore::InputError& e) {
      std::fprintf(stderr, "%s\n", e.formatted().c_str());
      return 1;
    }
  }
#endif
  out.flush();
  if (!out) {
    std::fprintf(stderr, "cncore-gen: write failed\n");
    return 1;
  }
  return 0;
}
