// Bad input → InputError with FILE:LINE:COL, never a crash.
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

struct Where {
  std::uint32_t line, col;
  std::string text;  // part of the message
};

// Parses, plans and runs; expects an InputError at `w`.
void expect_error(const std::vector<std::string>& texts, const Where& w, RunOptions o = {},
                  const MachineConfig& m = stiff_machine()) {
  try {
    run_texts(texts, o, m);
    ADD_FAILURE() << "no error for: " << texts.back();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), w.line) << e.formatted();
    EXPECT_EQ(e.col(), w.col) << e.formatted();
    EXPECT_NE(std::string(e.what()).find(w.text), std::string::npos) << e.formatted();
    EXPECT_EQ(e.formatted().rfind("t" + std::to_string(texts.size()) + ".tbl:", 0), 0U)
        << e.formatted();
  }
}

const std::string kHead = "REF TIME\nAXES X Z\n";

TEST(BadInput, ReferenceNotIncreasingAfterShift) {
  // L2000 SFT-1200 → 800, before the previous point at 1000.
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT-1200\n"}, {4, 1, "does not increase"});
  // Equal is not an increase either; and the shift carries to later rows.
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT-500\nL2500 X3\n  L2600 X4 SFT-100\n"},
               {6, 3, "does not increase"});
}

TEST(BadInput, ReferenceNotIncreasingWithoutShift) {
  expect_error({kHead + "L1000 X1\nL1000 X2\n"}, {4, 1, "does not increase"});
}

TEST(BadInput, ReferenceBeforeTheStart) {
  expect_error({kHead + "L-5 X1\n"}, {3, 1, "before the start"});
  expect_error({kHead + "L100 X1 SFT-200\n"}, {3, 1, "before the start"});
}

TEST(BadInput, UnknownAddress) {
  expect_error({kHead + "L1000 X1 Q5\n"}, {3, 10, "unknown address 'Q'"});
  expect_error({kHead + "L1000 X1 F100\n"}, {3, 10, "unknown address 'F'"});
  expect_error({kHead + "L1000 X1 SFTX\n"}, {3, 10, "missing amount after SFT"});
  expect_error({kHead + "L1000 X1 FOO\n"}, {3, 10, "unknown address"});
  expect_error({kHead + "L1000 X1 $\n"}, {3, 10, "unexpected character"});
}

TEST(BadInput, MissingAmount) {
  expect_error({kHead + "L1000 X1 SFT\n"}, {3, 10, "missing amount after SFT"});
  expect_error({kHead + "L1000 X1 SFT=\n"}, {3, 14, "SFT= needs P<n>, #<n> or R<n>"});
  expect_error({kHead + "L1000 X1 SFT=#\n"}, {3, 14, "missing number after SFT=#"});
  expect_error({kHead + "L1000 X1 SFT=R1.5\n"}, {3, 15, "whole number"});
  expect_error({kHead + "L X1\n"}, {3, 1, "missing reference value after L"});
  expect_error({kHead + "L1000 X\n"}, {3, 7, "missing value after X"});
  expect_error({kHead + "X1 Z2\n"}, {3, 1, "row without reference value L"});
}

TEST(BadInput, UndefinedParameterVariableSignal) {
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT=P7\n"}, {4, 10, "parameter P7 is not defined"});
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT=#501\n"},
               {4, 10, "macro variable #501 is not defined"});
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT=R1001\n"}, {4, 10, "signal R1001 is not defined"});
  // A signal that appears only later is undefined when the plan reads the row at t = 0.
  RunOptions o;
  o.values.signal_changes.push_back({0.5, 1001, -100});
  expect_error({kHead + "L1000 X1\nL2000 X2 SFT=R1001\n"}, {4, 10, "signal R1001"}, o);
}

TEST(BadInput, AxisNotConfigured) {
  MachineConfig m = stiff_machine();
  m.axes[kZ].enabled = false;
  expect_error({"REF TIME\nAXES X  Z\nL1000 X1\n"}, {2, 9, "axis Z is not configured"}, {}, m);
  // The master axis too.
  expect_error({"REF AXIS A\nAXES X\nL10 X1\n"}, {1, 1, "reference axis A is not configured"});
}

TEST(BadInput, AxisNotInTheTable) {
  expect_error({kHead + "L1000 X1 Y2\n"}, {3, 10, "axis Y is not driven by this table (AXES X Z)"});
}

TEST(BadInput, Header) {
  expect_error({"AXES X\nL1000 X1\n"}, {2, 1, "missing REF header"});
  expect_error({"REF TIME\nL1000 X1\n"}, {2, 1, "missing AXES header"});
  expect_error({"REF CLOCK\nAXES X\n"}, {1, 5, "unknown reference kind 'CLOCK'"});
  expect_error({"REF AXIS Q\nAXES X\n"}, {1, 10, "REF AXIS needs an axis letter"});
  expect_error({"REF TIME\nAXES X\nL1000 X1\nCUBIC\n"}, {4, 1, "before the first row"});
  expect_error({"REF TIME\nAXES X W\n"}, {2, 8, "'W' is not an axis"});
  expect_error({"REF TIME\nAXES X\n"}, {2, 1, "table has no rows"});
  expect_error({"REF TIME\nAXES X\nINTERPOLATE\n"}, {3, 1, "unknown word 'INTERPOLATE'"});
  expect_error({"REF AXIS X\nAXES X Z\nL10 Z1\n"}, {2, 6, "is the reference"});
  expect_error({"REF TIME\nAXES X\nCYCLIC 0\nL0 X0\nL10 X0\n"}, {3, 8, "at least 1"});
}

TEST(BadInput, Comments) {
  expect_error({kHead + "L1000 X1 (open\n"}, {3, 10, "not closed"});
  // Comments do not move the columns of what follows.
  expect_error({kHead + "(c) L1000 X1 ; ok\nL900 (x) X2\n"}, {4, 1, "does not increase"});
}

TEST(BadInput, CyclicMustClose) {
  expect_error({"REF TIME\nAXES X\nCYCLIC\nL0 X0\nL10 X1\n"}, {5, 1, "must end where it starts"});
}

TEST(BadInput, SeveralTables) {
  expect_error({"REF TIME\nAXES X\nL10 X1\n", "REF TIME\nAXES Z X\nL10 X1\n"},
               {2, 8, "axis X is already driven"});
  expect_error({"REF TIME\nAXES X\nL10 X1\n", "\nREF SPINDLE\nAXES Z\nL10 Z1\n"},
               {2, 1, "reference differs"});
}

TEST(BadInput, SftAndSftcanInOneRow) {
  expect_error({kHead + "L1000 X1 SFT-5 SFTCAN\n"}, {3, 16, "SFT and SFTCAN"});
}

TEST(BadInput, SignalChangeDuringTheRunMakesTheReferenceGoBack) {
  // Row 5 is read at 1.5 s (when the segment ending at it starts); by then R1001 = -900, so it
  // lands at 1100 ms, before row 4 (1500 ms). The samples before the error were delivered.
  RunOptions o;
  o.values.signals[1001] = 0;
  o.values.signal_changes.push_back({1.2, 1001, -900});
  std::vector<Table> t{parse_table(kHead + "L1000 X1\nL1500 X2\nL2000 X3 SFT=R1001\n", "sig.tbl")};
  TablePlan plan = plan_tables(t, stiff_machine(), o);
  EXPECT_FALSE(plan.has_errors());
  std::size_t delivered = 0;
  try {
    run_tables(plan, [&](const TableSample&) { ++delivered; });
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 5U);
    EXPECT_EQ(e.col(), 1U);
  }
  EXPECT_EQ(delivered, 1500U);  // t = 0 … 1.499 s
}

TEST(BadInput, SignalOptions) {
  auto s = parse_signal_at("1.5:R1001=-200", "--signal-at");
  EXPECT_DOUBLE_EQ(s.t_s, 1.5);
  EXPECT_EQ(s.number, 1001);
  EXPECT_DOUBLE_EQ(s.value, -200);
  auto [n, v] = parse_signal("R7=3", "--signal");
  EXPECT_EQ(n, 7);
  EXPECT_DOUBLE_EQ(v, 3);
  EXPECT_THROW(parse_signal("X7=3", "--signal"), InputError);
  EXPECT_THROW(parse_signal("R7", "--signal"), InputError);
  EXPECT_THROW(parse_signal_at("R7=3", "--signal-at"), InputError);
  EXPECT_THROW(parse_signal_at("-1:R7=3", "--signal-at"), InputError);
}

TEST(BadInput, MissingFile) {
  EXPECT_THROW(load_table("/nonexistent/table.tbl"), InputError);
}

}  // namespace
}  // namespace cncore::tables::test
