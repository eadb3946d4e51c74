// Settings that make no sense are configuration errors naming the key.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "feedcontrol/adaptive.hpp"

using namespace cncore::feed;
using cncore::InputError;

namespace {

// The key named by validate(), or "" when the settings pass.
std::string rejected_key(const std::function<void(AdaptiveSettings&)>& change,
                         double max_override_pct = 200) {
  AdaptiveSettings s;
  change(s);
  try {
    s.validate("machine.toml", max_override_pct);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "machine.toml");
    const std::string what = e.what();
    const std::string key = what.substr(0, what.find(':'));
    EXPECT_EQ(key, s.find_problem(max_override_pct)->key);
    return key;
  }
  return "";
}

}  // namespace

TEST(Settings, DefaultsAreValid) {
  EXPECT_EQ(rejected_key([](AdaptiveSettings&) {}), "");
  EXPECT_FALSE(AdaptiveSettings{}.find_problem());
}

TEST(Settings, BadValuesNameTheirKey) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.upper_pct = s.lower_pct; }),
            "adaptive.upper_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) {
              s.upper_pct = 50;
              s.lower_pct = 80;
            }),
            "adaptive.upper_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.upper_pct = 250; }, 200),
            "adaptive.upper_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.target_load_pct = -1; }),
            "adaptive.target_load_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) {
              s.antiwindup = AntiWindup::kBackCalculation;
              s.ki = 0;
            }),
            "adaptive.ki");
  EXPECT_EQ(rejected_key([&](AdaptiveSettings& s) { s.kp = nan; }), "adaptive.kp");
  EXPECT_EQ(rejected_key([&](AdaptiveSettings& s) { s.ki = inf; }), "adaptive.ki");
  EXPECT_EQ(rejected_key([&](AdaptiveSettings& s) { s.kd = -inf; }), "adaptive.kd");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.kd = -0.1; }), "adaptive.kd");
  EXPECT_EQ(rejected_key([&](AdaptiveSettings& s) { s.constant_pct = nan; }),
            "adaptive.constant_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.control_cycles = 0; }),
            "adaptive.control_cycles");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.lower_pct = -5; }), "adaptive.lower_pct");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) { s.threshold_pct = 70; }),
            "adaptive.threshold_pct");
}

TEST(Settings, KiZeroIsFineWithoutBackCalculation) {
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) {
              s.antiwindup = AntiWindup::kClamp;
              s.ki = 0;
            }),
            "");
  EXPECT_EQ(rejected_key([](AdaptiveSettings& s) {
              s.antiwindup = AntiWindup::kNone;
              s.ki = 0;
            }),
            "");
}

TEST(Settings, PolicyNames) {
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    EXPECT_EQ(parse_antiwindup(antiwindup_name(p)), p);
  }
  EXPECT_EQ(antiwindup_name(AntiWindup::kBackCalculation), "back_calculation");
  EXPECT_FALSE(parse_antiwindup("overwrite"));
  EXPECT_FALSE(parse_antiwindup(""));
}
