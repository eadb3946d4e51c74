// The closest-name suggestion for misspelled commands and options.
#include "app/suggest.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using cncore::app::closest_name;
using cncore::app::edit_distance;

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(edit_distance("", ""), 0u);
  EXPECT_EQ(edit_distance("run", "run"), 0u);
  EXPECT_EQ(edit_distance("", "run"), 3u);
  EXPECT_EQ(edit_distance("runn", "run"), 1u);              // insertion
  EXPECT_EQ(edit_distance("--overide", "--override"), 1u);  // deletion
  EXPECT_EQ(edit_distance("chack", "check"), 1u);           // substitution
  EXPECT_EQ(edit_distance("chekc", "check"), 1u);           // two neighbours swapped
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("table", "machine"), edit_distance("machine", "table"));
}

TEST(ClosestName, PicksTheNearestWithinAThirdOfTheWord) {
  const std::vector<std::string> commands{"run", "check", "table", "machine"};
  EXPECT_EQ(closest_name("runn", commands), "run");
  EXPECT_EQ(closest_name("tabel", commands), "table");
  EXPECT_EQ(closest_name("machien", commands), "machine");
  EXPECT_EQ(closest_name("frobnicate", commands), std::nullopt);
  EXPECT_EQ(closest_name("x", commands), std::nullopt);
  const std::vector<std::string> options{"--override", "--override-at", "--trajectory"};
  EXPECT_EQ(closest_name("--overide", options), "--override");
  EXPECT_EQ(closest_name("--override-a", options), "--override-at");
  EXPECT_EQ(closest_name("--trajectroy", options), "--trajectory");
  EXPECT_EQ(closest_name("--summary", options), std::nullopt);
}

}  // namespace
