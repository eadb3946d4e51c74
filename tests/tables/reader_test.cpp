// The reader's view of a table, and the effective listing (--print-effective) read back.
#include <gtest/gtest.h>

#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

TEST(Reader, HeaderRowsCommentsAndWords) {
  Table t = parse_table(
      "% \n; a table\n(header follows)\nref axis y\nAXES X,Z\nCUBIC\nCYCLIC 4\n"
      "N10 L0 X0 Z0 (start)\nl1000 x1.5 z-.5 m8 M9 ; two M codes\n"
      "L2000 SFT-200.5\nL3000 SFT = P12\nL4000 SFT=#501\nL5000 SFT=R1001\nL6000 X0 Z0 SFTCAN\n",
      "r.tbl");
  EXPECT_EQ(t.ref_kind, RefKind::kAxis);
  EXPECT_EQ(t.ref_axis, kY);
  EXPECT_EQ(t.ref_line, 4U);
  EXPECT_EQ(t.axis_mask, (1U << kX) | (1U << kZ));
  EXPECT_EQ(t.interp, Interp::kCubic);
  EXPECT_TRUE(t.cyclic);
  EXPECT_EQ(t.cyclic_repeats, 4U);
  ASSERT_EQ(t.rows.size(), 7U);
  EXPECT_EQ(t.rows[0].line, 8U);
  EXPECT_EQ(t.rows[0].col, 5U);
  EXPECT_DOUBLE_EQ(t.rows[1].target[kX], 1.5);
  EXPECT_DOUBLE_EQ(t.rows[1].target[kZ], -0.5);
  EXPECT_EQ(t.rows[1].m_codes, (std::vector<int>{8, 9}));
  EXPECT_EQ(t.rows[2].axis_mask, 0U);
  EXPECT_EQ(t.rows[2].shift.kind, Shift::Kind::kDirect);
  EXPECT_DOUBLE_EQ(t.rows[2].shift.amount, -200.5);
  EXPECT_EQ(t.rows[3].shift.kind, Shift::Kind::kParam);
  EXPECT_EQ(t.rows[3].shift.number, 12);
  EXPECT_EQ(t.rows[4].shift.kind, Shift::Kind::kMacro);
  EXPECT_EQ(t.rows[4].shift.number, 501);
  EXPECT_EQ(t.rows[5].shift.kind, Shift::Kind::kSignal);
  EXPECT_EQ(t.rows[5].shift.number, 1001);
  EXPECT_TRUE(t.rows[6].cancel);
  EXPECT_EQ(t.rows[6].cancel_col, 13U);
}

// Printing the effective table and reading it back gives the same motion.
void expect_round_trip(const std::vector<std::string>& texts, const RunOptions& o) {
  TableRun a = run_texts(texts, o);
  std::string listing = format_effective(a.plan);
  // One table per block of the listing (separated by blank lines).
  std::vector<std::string> back;
  std::size_t pos = 0;
  while (pos < listing.size()) {
    std::size_t e = listing.find("\n\n", pos);
    back.push_back(listing.substr(pos, e - pos + 1));
    pos = e + 2;
  }
  ASSERT_EQ(back.size(), texts.size()) << listing;
  RunOptions plain = o;
  plain.settings.cancel_mode = CancelMode::kClear;  // no SFT left in the listing
  TableRun b = run_texts(back, plain);
  ASSERT_EQ(a.samples.size(), b.samples.size()) << listing;
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    for (std::size_t ax = 0; ax < kMaxAxes; ++ax) {
      ASSERT_NEAR(a.samples[i].position[ax], b.samples[i].position[ax], 1e-9) << listing;
    }
  }
}

TEST(Effective, ListingReadsBackAsTheSameMotion) {
  RunOptions o;
  o.settings.cancel_mode = CancelMode::kRebase;
  o.values.macros[7] = -150;
  expect_round_trip({"REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=#7\nL3000 X300 SFTCAN\n"
                     "L4000 X400 M5\n",
                     "REF TIME\nAXES Z\nCUBIC\nL0 Z0\nL1500 Z-20 SFT-100\nL2500 Z-30\n"},
                    o);
}

TEST(Effective, ListingShowsWrittenAndShiftedValues) {
  TableRun r = run_texts({"REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT-200\nL3000 X300\n"});
  std::string s = format_effective(r.plan);
  EXPECT_NE(s.find("L1800 X200"), std::string::npos) << s;
  EXPECT_NE(s.find("written L2000"), std::string::npos) << s;
  EXPECT_NE(s.find("L2800 X300"), std::string::npos) << s;
  EXPECT_NE(s.find("; start: L0 X0"), std::string::npos) << s;
}

}  // namespace
}  // namespace cncore::tables::test
