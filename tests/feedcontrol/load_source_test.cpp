// Recorded load files (interpolation, rejections with FILE:LINE:COL) and the plant model.
#include "feedcontrol/load_source.hpp"

#include <gtest/gtest.h>
#include <rapidcheck.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"

using namespace cncore::feed;
using cncore::InputError;

namespace {

// The InputError of parsing text, as "LINE:COL: MESSAGE" (empty when it parses).
std::string reject(const std::string& text) {
  try {
    RecordedLoad::parse(text, "load.csv");
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "load.csv");
    return std::to_string(e.line()) + ":" + std::to_string(e.col()) + ": " + e.what();
  }
  return "";
}

}  // namespace

TEST(RecordedLoad, TimeInterpolatesLinearlyAndHoldsOutside) {
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,10\n1,30\n3,20\n", "load.csv");
  EXPECT_EQ(rec.axis(), RecordedLoad::Axis::kTime);
  ASSERT_EQ(rec.size(), 3u);
  EXPECT_DOUBLE_EQ(rec.load_pct(-1, 99, 0), 10);
  EXPECT_DOUBLE_EQ(rec.load_pct(0.5, 99, 0), 20);
  EXPECT_DOUBLE_EQ(rec.load_pct(1, 99, 0), 30);
  EXPECT_DOUBLE_EQ(rec.load_pct(2.5, 99, 0), 22.5);
  EXPECT_DOUBLE_EQ(rec.load_pct(7, 99, 0), 20);
  EXPECT_DOUBLE_EQ(rec.at(std::nan("")), 10);  // no crash on a NaN abscissa
}

TEST(RecordedLoad, DistanceUsesThePathNotTheTime) {
  auto rec = RecordedLoad::parse("# spindle log\ns_mm , load_pct\r\n\n0, 0\n10,50\n", "load.csv");
  EXPECT_EQ(rec.axis(), RecordedLoad::Axis::kDistance);
  EXPECT_DOUBLE_EQ(rec.load_pct(100, 4, 0), 20);
}

TEST(RecordedLoad, EqualAbscissaIsAStep) {
  auto rec = RecordedLoad::parse("s_mm,load_pct\n0,10\n5,10\n5,40\n10,40\n", "load.csv");
  EXPECT_DOUBLE_EQ(rec.at(4.999), 10);
  EXPECT_DOUBLE_EQ(rec.at(5), 40);
}

TEST(RecordedLoad, RejectsWithLineAndColumn) {
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n1,\n"), "3:3: empty load field");
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n,20\n"), "3:1: empty time field");
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n1,abc\n"), "3:3: load is not a number: 'abc'");
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n1,12x\n"), "3:3: load is not a number: '12x'");
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n2,20\n1.5,30\n"),
            "4:1: time goes backwards (1.5 after 2.000000)");
  EXPECT_EQ(reject("s_mm,load_pct\n0,10\n-1,20\n"),
            "3:1: distance goes backwards (-1 after 0.000000)");
  EXPECT_EQ(reject("t_s,load_pct\n0,10\n1,nan\n"), "3:3: load must be finite");
  EXPECT_EQ(reject("t_s,load_pct\n0,-3\n"), "2:3: load must not be negative");
  EXPECT_EQ(reject("t_s,load_pct\n0,1,2\n"), "2:5: expected 2 fields, found 3");
  EXPECT_EQ(reject("t_s,load_pct\n0\n"), "2:2: expected 2 fields (time, load), found 1");
  EXPECT_EQ(reject("time,load_pct\n0,1\n"),
            "1:1: first column must be 't_s' (time) or 's_mm' (path distance), not 'time'");
  EXPECT_EQ(reject("t_s,load\n"), "1:5: second column must be 'load_pct', not 'load'");
  EXPECT_EQ(reject("t_s,load_pct\n"), "1:1: load file has no data rows");
  EXPECT_EQ(reject(""), "1:1: empty load file: no header");
}

TEST(RecordedLoad, LoadsAFileAndNamesAMissingOne) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / "cncore_feedcontrol_load_test.csv").string();
  {
    std::ofstream out(path);
    out << "t_s,load_pct\n0,10\n2,30\n";
  }
  EXPECT_DOUBLE_EQ(RecordedLoad::load(path).at(1), 20);
  std::remove(path.c_str());
  try {
    RecordedLoad::load(path);
    FAIL() << "missing file accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

namespace {

PlantSettings quiet_plant() {
  PlantSettings p;
  p.base_pct = 5;
  p.k_pct_per_mm2_min = 0.04;
  p.time_constant_s = 0;
  p.noise_pct = 0;
  p.depth.s_mm = {0, 10, 10, 20};
  p.depth.depth_mm = {0, 0, 1, 2};
  return p;
}

}  // namespace

TEST(PlantLoad, StaticLoadIsBasePlusKFeedDepth) {
  PlantLoad plant(quiet_plant());
  EXPECT_DOUBLE_EQ(plant.load_pct(0, 5, 1000), 5);          // air: base load
  EXPECT_DOUBLE_EQ(plant.load_pct(0.1, 10, 1000), 5 + 40);  // after the jump: 1 mm
  EXPECT_DOUBLE_EQ(plant.load_pct(0.2, 15, 1000), 5 + 0.04 * 1000 * 1.5);
  EXPECT_DOUBLE_EQ(plant.load_pct(0.3, 30, 500), 5 + 0.04 * 500 * 2);  // held after the end
}

TEST(PlantLoad, FirstOrderLagReaches63PercentAfterOneTimeConstant) {
  PlantSettings p = quiet_plant();
  p.time_constant_s = 0.1;
  PlantLoad plant(p);
  plant.load_pct(0, 15, 0);  // at rest: base load
  double load = 0;
  for (int n = 1; n <= 100; ++n) load = plant.load_pct(n * 0.001, 15, 1000);  // step to 65 %
  // 5 + 60·(1 − e^−1) = 42.93 at t = τ.
  EXPECT_NEAR(load, 5 + 60 * (1 - std::exp(-1.0)), 1e-9);
  for (int n = 101; n <= 1000; ++n) load = plant.load_pct(n * 0.001, 15, 1000);
  EXPECT_NEAR(load, 65, 65 * std::exp(-10.0) + 1e-9);
}

TEST(PlantLoad, NoiseIsSeededGaussianWithTheGivenSpread) {
  PlantSettings p = quiet_plant();
  p.noise_pct = 2;
  p.seed = 11;
  PlantLoad a(p), b(p);
  p.seed = 12;
  PlantLoad c(p);
  double sum = 0, sum2 = 0;
  bool differs = false;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double la = a.load_pct(i * 0.001, 15, 1000);
    EXPECT_EQ(la, b.load_pct(i * 0.001, 15, 1000));
    differs |= la != c.load_pct(i * 0.001, 15, 1000);
    sum += la - 65;
    sum2 += (la - 65) * (la - 65);
  }
  EXPECT_TRUE(differs);
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0, 0.05);  // 3.5 standard errors (2/√20000 = 0.014)
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), 2, 0.05);
}

TEST(PlantLoad, BadSettingsNameTheKey) {
  PlantSettings p = quiet_plant();
  p.time_constant_s = -1;
  ASSERT_TRUE(p.find_problem());
  EXPECT_EQ(p.find_problem()->key, "adaptive.plant.time_constant_s");
  p = quiet_plant();
  p.depth.s_mm = {0, 10, 5};
  p.depth.depth_mm = {0, 1, 1};
  ASSERT_TRUE(p.find_problem());
  EXPECT_EQ(p.find_problem()->key, "adaptive.plant.depth");
  EXPECT_NE(p.find_problem()->message.find("point 3"), std::string::npos);
  p.depth.s_mm = {0};
  EXPECT_TRUE(p.find_problem());  // lengths differ
  p.depth.depth_mm = {-1};
  EXPECT_TRUE(p.find_problem());
  p.depth.depth_mm = {1};
  EXPECT_FALSE(p.find_problem());
  p.noise_pct = std::nan("");
  EXPECT_THROW(p.validate(), InputError);
}

// Any text either loads or is rejected with InputError: never a crash, never another exception.
TEST(RecordedLoad, ArbitraryTextLoadsOrIsRejected) {
  const bool ok = rc::check([] {
    const auto lines = *rc::gen::container<std::vector<std::string>>(rc::gen::oneOf(
        rc::gen::element<std::string>("t_s,load_pct", "s_mm,load_pct", "", "# c", "1,2", ",", "3,",
                                      "x,1", "1e400,1", "-1,5", "2,-0", " 4 , 5 ", "5,6,7"),
        rc::gen::arbitrary<std::string>()));
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    try {
      const auto rec = RecordedLoad::parse(text, "load.csv");
      RC_ASSERT(rec.size() > 0u);
      RC_ASSERT(std::isfinite(rec.at(0.5)));
    } catch (const InputError& e) {
      RC_ASSERT(e.line() >= 1u);
    }
  });
  EXPECT_TRUE(ok);
}
