// RapidCheck properties. Random valid programs (G0/G1/G2/G3 in random planes with I/J/K or R,
// G90/G91, G20/G21, work offsets) interpret without error, every block is consistent (arc
// radius equal at start and end, positive lengths, end of one motion block = start of the
// next) and every motion ends where the generator (an independent model of the program) put
// it. Random garbage never throws anything but InputError.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

struct Generated {
  std::string text;
  std::vector<AxisVec> ends;  // expected machine end of every motion block, in order
};

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

// Builds a random valid program while tracking the machine state independently of the
// interpreter: position (machine mm), units, distance mode, offsets of G54/G55.
Generated generate_program() {
  Generated g;
  AxisVec pos;  // machine mm
  bool inch = false, incremental = false;
  int system = 1;
  std::array<std::array<double, 3>, 2> offsets{};  // G54, G55 (mm)
  for (auto& o : offsets) {
    o = {*rc::gen::inRange(-200, 201) / 10.0, *rc::gen::inRange(-200, 201) / 10.0,
         *rc::gen::inRange(-100, 101) / 10.0};
  }
  g.text += "G21 G90 F500\n";
  g.text += "G10 L2 P1 X" + num(offsets[0][0]) + " Y" + num(offsets[0][1]) + " Z" +
            num(offsets[0][2]) + "\n";
  g.text += "G10 L2 P2 X" + num(offsets[1][0]) + " Y" + num(offsets[1][1]) + " Z" +
            num(offsets[1][2]) + "\n";
  const int n = *rc::gen::inRange(1, 40);
  auto coord = [] { return *rc::gen::inRange(-600, 601) / 10.0; };  // mm, within ±60
  // The words that put axis `a` at machine position `target` (in the current modes).
  auto word = [&](std::size_t a, double target) {
    const double unit = inch ? 25.4 : 1.0;
    const double off = offsets[static_cast<std::size_t>(system - 1)][a];
    const double v = incremental ? (target - pos[a]) / unit : (target - off) / unit;
    return std::string(1, "XYZ"[a]) + num(v);
  };
  // Rounding the words to 4 decimals moves the real end: model what the interpreter reads.
  auto read_back = [&](std::size_t a, double target) {
    const double unit = inch ? 25.4 : 1.0;
    const double off = offsets[static_cast<std::size_t>(system - 1)][a];
    const std::string w = word(a, target);
    const double v = std::stod(w.substr(1)) * unit;
    return incremental ? pos[a] + v : v + off;
  };
  for (int i = 0; i < n; ++i) {
    switch (*rc::gen::inRange(0, 6)) {
      case 0:
        inch = !inch;
        g.text += inch ? "G20\n" : "G21\n";
        break;
      case 1:
        incremental = !incremental;
        g.text += incremental ? "G91\n" : "G90\n";
        break;
      case 2:
        system = 3 - system;
        g.text += system == 1 ? "G54\n" : "G55\n";
        break;
      case 3:
      case 4: {  // straight move
        const bool rapid = *rc::gen::arbitrary<bool>();
        AxisVec target = pos;
        for (std::size_t a = 0; a < 3; ++a) {
          if (*rc::gen::arbitrary<bool>()) target[a] = coord();
        }
        std::string line = rapid ? "G0" : "G1";
        AxisVec t2 = pos;
        for (std::size_t a = 0; a < 3; ++a) {
          if (target[a] != pos[a]) {
            line += " " + word(a, target[a]);
            t2[a] = read_back(a, target[a]);
          }
        }
        g.text += line + "\n";
        double len2 = 0;
        for (std::size_t a = 0; a < 3; ++a) len2 += (t2[a] - pos[a]) * (t2[a] - pos[a]);
        if (len2 > 1e-18) g.ends.push_back(t2);
        pos = t2;
        break;
      }
      default: {  // arc
        const int plane = *rc::gen::inRange(0, 3);
        const std::size_t p = plane == 0 ? 0 : plane == 1 ? 2 : 1;  // first axis
        const std::size_t q = plane == 0 ? 1 : plane == 1 ? 0 : 2;  // second axis
        const std::size_t nrm = 3 - p - q;
        const char* pw = plane == 0 ? "I" : plane == 1 ? "K" : "J";
        const char* qw = plane == 0 ? "J" : plane == 1 ? "I" : "K";
        const double r = *rc::gen::inRange(20, 301) / 10.0;
        const double phi = *rc::gen::inRange(0, 360) * std::numbers::pi / 180;
        const double theta = *rc::gen::inRange(5, 356) * std::numbers::pi / 180;  // sweep
        const bool ccw = *rc::gen::arbitrary<bool>();
        const bool use_r = *rc::gen::arbitrary<bool>();
        const double ca = pos[p] + r * std::cos(phi), cb = pos[q] + r * std::sin(phi);
        const double a0 = std::atan2(pos[q] - cb, pos[p] - ca);
        const double a1 = ccw ? a0 + theta : a0 - theta;
        AxisVec target = pos;
        target[p] = ca + r * std::cos(a1);
        target[q] = cb + r * std::sin(a1);
        const bool helix = *rc::gen::arbitrary<bool>();
        if (helix) target[nrm] = pos[nrm] + *rc::gen::inRange(-50, 51) / 10.0;
        // Keep the whole circle inside the ±100 mm box used by the generator.
        if (std::fabs(ca) + r > 95 || std::fabs(cb) + r > 95 || std::fabs(target[nrm]) > 95) break;
        const double unit = inch ? 25.4 : 1.0;
        std::string line = ccw ? "G3" : "G2";
        line += plane == 0 ? " G17" : plane == 1 ? " G18" : " G19";
        AxisVec t2 = pos;
        line += " " + word(p, target[p]);
        t2[p] = read_back(p, target[p]);
        line += " " + word(q, target[q]);
        t2[q] = read_back(q, target[q]);
        if (helix) {
          line += " " + word(nrm, target[nrm]);
          t2[nrm] = read_back(nrm, target[nrm]);
        }
        if (use_r) {
          // R < 0 asks for the arc longer than a half circle.
          const double rr = theta > std::numbers::pi ? -r : r;
          if (std::fabs(theta - std::numbers::pi) < 0.05) break;  // ambiguous half circle
          line += " R" + num(rr / unit);
        } else {
          line += std::string(" ") + pw + num((ca - pos[p]) / unit);
          line += std::string(" ") + qw + num((cb - pos[q]) / unit);
        }
        g.text += line + "\n";
        g.ends.push_back(t2);
        pos = t2;
        break;
      }
    }
  }
  g.text += "M2\n";
  return g;
}

double plane_radius(const Block& b, const Vec3& p) {
  const Vec3 d = p - b.center;
  const Vec3 along = dot(d, b.normal) * b.normal;
  return norm(d - along);
}

RC_GTEST_PROP(InterpreterProperties, RandomValidProgramsGiveConsistentBlocks, ()) {
  const Generated g = generate_program();
  const MachineConfig m = test_machine();
  std::vector<Block> blocks;
  try {
    Interpreter in(Interpreter::FromText{}, g.text, "random.ngc", m, Options{});
    Block b;
    while (in.next(b)) blocks.push_back(b);
  } catch (const InputError& e) {
    RC_FAIL("valid program rejected: " + e.formatted() + "\n" + g.text);
  }
  std::size_t k = 0;
  bool have_prev = false;
  AxisVec prev;
  for (const Block& b : blocks) {
    if (b.kind != BlockKind::kRapid && b.kind != BlockKind::kLine && b.kind != BlockKind::kArc) {
      continue;
    }
    if (have_prev) RC_ASSERT(b.start == prev);
    prev = b.end;
    have_prev = true;
    RC_ASSERT(k < g.ends.size());
    for (std::size_t a = 0; a < 3; ++a) RC_ASSERT(std::fabs(b.end[a] - g.ends[k][a]) < 1e-6);
    ++k;
    if (b.kind == BlockKind::kArc) {
      RC_ASSERT(std::fabs(norm(b.normal) - 1) < 1e-12);
      const double r0 = plane_radius(b, b.start.xyz());
      const double r1 = plane_radius(b, b.end.xyz());
      RC_ASSERT(r0 > 0);
      // The words are written rounded: an I J K arc keeps its programmed centre (a spiral,
      // as in LinuxCNC), so its radii differ by that rounding only.
      RC_ASSERT(std::fabs(r1 - r0) <= 5e-3);
      // The centre lies in the plane of the start point.
      RC_ASSERT(std::fabs(dot(b.start.xyz() - b.center, b.normal)) < 1e-12);
    } else {
      RC_ASSERT(norm(b.end.xyz() - b.start.xyz()) > 0);
    }
  }
  RC_ASSERT(k == g.ends.size());
}

// Random text from the G-code alphabet: never a crash, never an exception but InputError.
RC_GTEST_PROP(InterpreterProperties, GarbageOnlyEverThrowsInputError, ()) {
  static const std::string kAlphabet = "GMXYZIJKRFPLSTON#<>[]()=+-*/.;%0123456789 \n\tabcdefo@^_";
  const auto chars = *rc::gen::container<std::vector<std::size_t>>(
      rc::gen::inRange<std::size_t>(0, kAlphabet.size()));
  std::string text;
  for (std::size_t i : chars) text.push_back(kAlphabet[i]);
  MachineConfig m = test_machine();
  m.max_loop_iterations = 1000;
  try {
    Interpreter in(Interpreter::FromText{}, text, "garbage.ngc", m, Options{});
    Block b;
    for (int i = 0; i < 100000 && in.next(b); ++i) {
    }
  } catch (const InputError& e) {
    RC_ASSERT(e.line() >= 1u);
    RC_ASSERT(e.col() >= 1u);
  }
}

// Mutations of a valid program (one character replaced) are either valid or InputError.
RC_GTEST_PROP(InterpreterProperties, MutatedProgramsOnlyThrowInputError, ()) {
  std::string text =
      "G21 G90 F300\nG0 X10 Y5\no1 sub\nG2 X0 Y-5 I-5 J-5\no1 endsub\n#<a>=[2*SIN[30]]\n"
      "o2 repeat [3]\no1 call [1]\nG1 X[#<a>*10]\no2 endrepeat\nG18 G3 X10 Z0 R5\nM30\n";
  const std::size_t at = *rc::gen::inRange<std::size_t>(0, text.size());
  const char c =
      *rc::gen::element('G', 'X', '[', ']', '#', '(', ';', '9', '.', '-', 'o', '/', '\n', 'R');
  text[at] = c;
  MachineConfig m = test_machine();
  m.max_loop_iterations = 1000;
  try {
    Interpreter in(Interpreter::FromText{}, text, "mutated.ngc", m, Options{});
    Block b;
    for (int i = 0; i < 100000 && in.next(b); ++i) {
    }
  } catch (const InputError& e) {
    RC_ASSERT(e.line() >= 1u);
  }
}

}  // namespace
}  // namespace cncore::interp::test
