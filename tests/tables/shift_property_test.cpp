// Property: for random tables with random SFT / SFTCAN, every control point is reached at the
// reference value the spec's rules give (an independent model below), the motion between points
// is linear, and tables whose shifted references do not increase are rejected at the right row.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <cctype>
#include <string>

#include "core/error.hpp"
#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

struct GenRow {
  int gap_ms;  // written L minus the previous written L (first: minus 0)
  int x;
  int kind;  // 0 none, 1 SFT, 2 SFTCAN
  int amount;
};

RC_GTEST_PROP(ShiftProperty, ControlPointsAreReachedWhereTheSpecSays, ()) {
  const bool rebase = *rc::gen::arbitrary<bool>();
  const auto rows = *rc::gen::container<std::vector<GenRow>>(
      *rc::gen::inRange<std::size_t>(1, 8),
      rc::gen::build<GenRow>(
          rc::gen::set(&GenRow::gap_ms, rc::gen::inRange(1, 800)),
          rc::gen::set(&GenRow::x, rc::gen::inRange(-100, 101)),
          rc::gen::set(&GenRow::kind, rc::gen::weightedElement<int>({{6, 0}, {3, 1}, {2, 2}})),
          rc::gen::set(&GenRow::amount, rc::gen::inRange(-400, 401))));

  // The model, straight from spec 02: clear → amount back to 0; rebase → the running reference
  // is reset by the amount, so what was shifted stays shifted (kept in `base`).
  std::string text = "REF TIME\nAXES X\n";
  std::vector<long> eff;
  long written = 0, amount = 0, base = 0, prev = 0;
  int bad_line = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const GenRow& r = rows[i];
    written += r.gap_ms;
    text += "L" + std::to_string(written) + " X" + std::to_string(r.x);
    if (r.kind == 1) {
      text += " SFT" + std::to_string(r.amount);
      amount += r.amount;
    } else if (r.kind == 2) {
      text += " SFTCAN";
      if (rebase) base += amount;
      amount = 0;
    }
    text += "\n";
    long e = written + amount + base;
    bool ok = i == 0 ? e >= 0 : e > prev;
    if (!ok && bad_line == 0) bad_line = static_cast<int>(i) + 3;
    eff.push_back(e);
    prev = e;
  }

  RC_CLASSIFY(bad_line != 0, "rejected");
  RC_CLASSIFY(rebase, "rebase");
  RunOptions o;
  o.settings.cancel_mode = rebase ? CancelMode::kRebase : CancelMode::kClear;
  MachineConfig m = stiff_machine();
  m.axes[kX].max_speed_mm_min = 1e12;  // this property is about timing, not limits
  m.axes[kX].max_accel_mm_s2 = 1e12;
  if (bad_line != 0) {
    try {
      run_texts({text}, o, m);
      RC_FAIL("accepted a table whose references do not increase:\n" + text);
    } catch (const InputError& e) {
      RC_ASSERT(e.line() == static_cast<std::uint32_t>(bad_line));
    }
    return;
  }
  TableRun run = run_texts({text}, o, m);
  RC_ASSERT(std::abs(run.samples.back().t_s - static_cast<double>(eff.back()) / 1000) < 1e-9);
  long prev_t = 0;
  double prev_x = eff.front() == 0 ? rows.front().x : 0.0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    // At the point itself (effective references are whole ms = whole cycles)…
    const TableSample& s = run.samples.at(static_cast<std::size_t>(eff[i]));
    RC_ASSERT(std::abs(s.position[kX] - rows[i].x) < 1e-9);
    // …and half-way from the previous point, on the straight line.
    if (eff[i] - prev_t >= 2 && (eff[i] - prev_t) % 2 == 0) {
      const TableSample& mid = run.samples.at(static_cast<std::size_t>((eff[i] + prev_t) / 2));
      RC_ASSERT(std::abs(mid.position[kX] - (prev_x + rows[i].x) / 2.0) < 1e-9);
    }
    prev_t = eff[i];
    prev_x = rows[i].x;
  }
}

}  // namespace
}  // namespace cncore::tables::test

namespace cncore::tables::test {
namespace {

// Robustness: any text made of table words (valid or not) either runs or fails with
// InputError naming the file.
RC_GTEST_PROP(ReaderProperty, ArbitraryTextIsAcceptedOrRejectedCleanly, ()) {
  const std::vector<std::string> words = {
      "L",      "X",      "Z",      "Y",        "M7",          "N5",     "SFT", "SFT=",
      "SFT=#1", "SFT=P1", "SFT=R1", "SFT=#9",   "SFTCAN",      "Q1",     "(c)", "(",
      ";c",     "CUBIC",  "CYCLIC", "CYCLIC 2", "REF SPINDLE", "AXES X", "%",   "\n",
      "\n",     "\n",     "\n",     "\n",       "\n",          "-",      ".",   "E5"};
  auto tokens = *rc::gen::container<std::vector<std::string>>(rc::gen::oneOf(
      rc::gen::elementOf(words),
      rc::gen::map(rc::gen::inRange(-50, 3000), [](int v) { return std::to_string(v); })));
  std::string text = *rc::gen::arbitrary<bool>() ? "REF TIME\nAXES X Z\nL0 X0 Z0\n" : "";
  for (const auto& tok : tokens) {
    bool glue = !tok.empty() && (std::isdigit(static_cast<unsigned char>(tok[0])) || tok[0] == '-');
    text += (glue ? "" : " ") + tok;
  }
  RunOptions o;
  o.values.params[1] = -5;
  o.values.macros[1] = 5;
  o.values.signals[1] = 1;
  MachineConfig m = stiff_machine();
  try {
    std::vector<Table> t{parse_table(text, "f.tbl")};
    TablePlan plan = plan_tables(t, m, o);
    RC_ASSERT(!plan.effective.empty());
    bool short_run = plan.effective[0].back().ref < 5000;
    RC_CLASSIFY(!plan.has_errors(), "planned");
    if (!plan.has_errors() && short_run) {
      std::size_t n = 0;
      run_tables(plan, [&](const TableSample&) { ++n; });
      RC_ASSERT(n >= 1U);
    }
  } catch (const InputError& e) {
    RC_ASSERT(e.formatted().rfind("f.tbl:", 0) == 0);
  }
}

}  // namespace
}  // namespace cncore::tables::test
