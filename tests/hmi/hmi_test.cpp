// The web page's server side without HTTP: arcs drawn as chords, the program's polyline and its
// JSON, the status event, and controls turned into controller calls with the controller's
// answers.
#include "hmi/hmi.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>

#include "hmi/api.hpp"
#include "hmi/program_view.hpp"

namespace cncore::hmi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

double angle_of(const Vec3& p) {
  return std::atan2(p.y, p.x);
}

TEST(ArcPoints, QuarterCounterClockwiseStaysOnTheCircleAndEndsAtTheEnd) {
  const auto pts =
      arc_points({10, 0, 0}, {0, 10, 0}, {0, 0, 0}, {0, 0, 1}, 0, 5 * std::numbers::pi / 180);
  ASSERT_EQ(pts.size(), 18U);  // 90° in chords of 5°
  double last = 0;
  for (const Vec3& p : pts) {
    EXPECT_NEAR(std::hypot(p.x, p.y), 10, 1e-9);
    EXPECT_GT(angle_of(p), last);  // counter-clockwise: the angle grows
    last = angle_of(p);
  }
  EXPECT_EQ(pts.back(), (Vec3{0, 10, 0}));
}

TEST(ArcPoints, ClockwiseAboutMinusZTurnsTheShortWay) {
  const auto pts =
      arc_points({10, 0, 0}, {0, -10, 0}, {0, 0, 0}, {0, 0, -1}, 0, 5 * std::numbers::pi / 180);
  ASSERT_EQ(pts.size(), 18U);
  for (const Vec3& p : pts) EXPECT_LE(p.y, 1e-9);  // through the fourth quadrant only
}

TEST(ArcPoints, FullCircleAndExtraTurnsOfAHelixRiseLinearly) {
  const double step = 10 * std::numbers::pi / 180;
  EXPECT_EQ(arc_points({5, 0, 0}, {5, 0, 0}, {0, 0, 0}, {0, 0, 1}, 0, step).size(), 36U);
  const auto helix = arc_points({5, 0, 0}, {5, 0, 6}, {0, 0, 0}, {0, 0, 1}, 2, step);
  ASSERT_EQ(helix.size(), 108U);  // three turns
  for (std::size_t i = 0; i < helix.size(); ++i) {
    EXPECT_NEAR(helix[i].z, 6.0 * static_cast<double>(i + 1) / 108, 1e-9);
    EXPECT_NEAR(std::hypot(helix[i].x, helix[i].y), 5, 1e-9);
  }
}

fs::path write_program(const std::string& name, const std::string& text) {
  fs::path p = fs::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(p) << text;
  return p;
}

TEST(ProgramView, PolylineKindsFeedsAndLinesAsTheJsonCarriesThem) {
  const fs::path p = write_program("view.ngc",
                                   "G21 G90\n"
                                   "G0 X10 Y0\n"
                                   "G1 X20 F1200\n"
                                   "G3 X10 Y10 I-10 J0 F600\n"
                                   "M30\n");
  AxisVec offset;
  offset[kX] = 100;
  const ProgramView v(p.string(), "view.ngc", default_machine_config(), offset);
  const auto& vs = v.vertices();
  // Start, the rapid's end, the line's end, 18 chords of the quarter arc.
  ASSERT_EQ(vs.size(), 3U + 18U);
  EXPECT_EQ(vs[0].kind, 2);
  EXPECT_EQ(vs[1].kind, 0);
  EXPECT_DOUBLE_EQ(vs[1].p.x, 110);  // shifted by the offset
  EXPECT_EQ(vs[2].kind, 1);
  EXPECT_EQ(vs[2].line, 3U);
  EXPECT_FLOAT_EQ(vs[2].feed_mm_min, 1200);
  EXPECT_EQ(vs.back().line, 4U);
  EXPECT_NEAR(vs.back().p.x, 110, 1e-9);
  EXPECT_NEAR(vs.back().p.y, 10, 1e-9);
  EXPECT_DOUBLE_EQ(v.feed_at_line(3), 1200);
  EXPECT_DOUBLE_EQ(v.feed_at_line(4), 600);
  EXPECT_DOUBLE_EQ(v.feed_at_line(2), 0);    // a rapid
  EXPECT_DOUBLE_EQ(v.feed_at_line(999), 0);  // beyond the program
  const json j = json::parse(v.json());
  EXPECT_EQ(j["name"], "view.ngc");
  EXPECT_EQ(j["vertices"], vs.size());
  EXPECT_EQ(j["xyz"].size(), 3 * vs.size());
  EXPECT_EQ(j["kind"].size(), vs.size());
  EXPECT_EQ(j["line"][2], 3);
  EXPECT_EQ(j["text"].get<std::string>().substr(0, 7), "G21 G90");
  EXPECT_FALSE(j["truncated"]);
}

TEST(Address, LoopbackAndSplitting) {
  EXPECT_TRUE(is_loopback("127.0.0.1"));
  EXPECT_TRUE(is_loopback("127.4.5.6"));
  EXPECT_TRUE(is_loopback("::1"));
  EXPECT_TRUE(is_loopback("localhost"));
  EXPECT_FALSE(is_loopback("0.0.0.0"));
  EXPECT_FALSE(is_loopback("192.168.1.20"));
  EXPECT_EQ(split_address("127.0.0.1:8080"),
            (std::pair<std::string, std::uint16_t>{"127.0.0.1", 8080}));
  EXPECT_EQ(split_address("[::1]:0"), (std::pair<std::string, std::uint16_t>{"::1", 0}));
  EXPECT_THROW(split_address("127.0.0.1"), std::runtime_error);
  EXPECT_THROW(split_address("127.0.0.1:http"), std::runtime_error);
  EXPECT_THROW(split_address("127.0.0.1:70000"), std::runtime_error);
}

class Controls : public ::testing::Test {
 protected:
  static runtime::ControllerOptions options() {
    runtime::ControllerOptions o;
    o.realtime = false;
    o.sample_ring = 0;
    return o;
  }
  void wait_idle() {
    for (int i = 0; i < 5000 && c_.status().state != runtime::MachineState::kIdle; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  MachineConfig machine_ = default_machine_config();
  runtime::Controller c_{machine_, options()};
};

TEST_F(Controls, EachControlIsAControllerCallWithItsAnswer) {
  EXPECT_EQ(control(c_, "override", R"({"feed_pct":50,"rapid_pct":25})").http_status, 200);
  EXPECT_EQ(c_.status().feed_override_pct, 50);
  EXPECT_EQ(c_.status().rapid_override_pct, 25);
  const Reply refused = control(c_, "override", R"({"feed_pct":900})");
  EXPECT_EQ(refused.http_status, 409);
  EXPECT_NE(json::parse(refused.body)["error"].get<std::string>().find("between"),
            std::string::npos);
  EXPECT_EQ(control(c_, "override", "{}").http_status, 400);
  EXPECT_EQ(control(c_, "override", "not json").http_status, 400);
  EXPECT_EQ(control(c_, "jog", R"({"axes":{"q":1}})").http_status, 400);
  EXPECT_EQ(control(c_, "jog", R"({"mode":"sideways","axes":{"x":1}})").http_status, 400);
  EXPECT_EQ(control(c_, "frobnicate", "{}").http_status, 404);
  EXPECT_EQ(control(c_, "start", "{}").http_status, 409);  // no program loaded
  EXPECT_EQ(control(c_, "switches", R"({"single_block":true})").http_status, 200);
  EXPECT_TRUE(c_.status().switches.single_block);
  EXPECT_FALSE(c_.status().switches.optional_stop);
  EXPECT_EQ(control(c_, "override", R"({"feed_pct":100})").http_status, 200);
  ASSERT_EQ(control(c_, "jog", R"({"mode":"inc","axes":{"x":2.5},"feed_mm_min":3000})").http_status,
            200);
  wait_idle();
  EXPECT_NEAR(c_.status().commanded[kX], 2.5, 1e-9);
  ASSERT_EQ(control(c_, "mdi", R"({"line":"G0 Y4"})").http_status, 200);
  wait_idle();
  EXPECT_NEAR(c_.status().commanded[kY], 4, 1e-9);
  EXPECT_EQ(control(c_, "mdi", R"({"line":"G0 Y900"})").http_status, 409);  // beyond the travel
  EXPECT_EQ(control(c_, "estop", "").http_status, 200);
  EXPECT_EQ(c_.status().state, runtime::MachineState::kAlarm);
  EXPECT_EQ(control(c_, "unlock", "").http_status, 200);
  EXPECT_EQ(c_.status().state, runtime::MachineState::kIdle);
}

TEST_F(Controls, TheStatusEventCarriesWorkPositionsAndTheProgrammedFeed) {
  ASSERT_EQ(control(c_, "mdi", R"({"line":"G10 L2 P1 X1 Y2\nG54\nG0 X5 Y5"})").http_status, 200);
  wait_idle();
  const runtime::Status s = c_.status();
  const json j = json::parse(status_event_json(s, machine_, nullptr, 1.5));
  EXPECT_EQ(j["state"], "Idle");
  EXPECT_DOUBLE_EQ(j["machine"]["x"].get<double>(), s.commanded[kX]);
  EXPECT_DOUBLE_EQ(j["work"]["x"].get<double>(), s.commanded[kX] - s.work_offset[kX]);
  EXPECT_DOUBLE_EQ(j["work_offset"]["y"].get<double>(), s.work_offset[kY]);
  EXPECT_FALSE(j["machine"].contains("a"));  // only the enabled axes
  EXPECT_EQ(j["programmed_feed_mm_min"], 0.0);
  EXPECT_EQ(j["t"], 1.5);
}

// The height map as GET /api/heightmap sends it, read back the way the page's script reads it;
// the stock's controls on a machine with [stock] and without.
TEST(Heightmap, TheServedGridReadsBackAsThePageReadsIt) {
  MachineConfig m = parse_machine_config(R"(
[stock]
min_mm = [-10, -5, -8]
size_mm = [20, 10, 8]
cell_mm = 0.5
[[tools]]
number = 1
diameter_mm = 4
)",
                                         "stock.toml");
  runtime::ControllerOptions o;
  o.realtime = false;
  o.sample_ring = 0;
  runtime::Controller c(m, o);
  ASSERT_EQ(control(c, "mdi", R"({"line":"G0 X0 Y0 Z1\nG1 Z-2 F1000\nG0 Z1"})").http_status, 200);
  std::shared_ptr<const runtime::HeightMapGrid> g;
  for (int i = 0; i < 10000; ++i) {
    g = c.heightmap();
    if (g && g->heights_mm[10 * 40 + 20] < -1.999) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(g);
  const std::string b = heightmap_binary(*g);
  ASSERT_EQ(b.size(), 40 + 40 * 20 * 4U);
  EXPECT_EQ(b.substr(0, 8), "CNCZMAP1");
  std::uint32_t nx = 0, ny = 0;
  double x0 = 0, y0 = 0, cell = 0;
  std::memcpy(&nx, b.data() + 8, 4);
  std::memcpy(&ny, b.data() + 12, 4);
  std::memcpy(&x0, b.data() + 16, 8);
  std::memcpy(&y0, b.data() + 24, 8);
  std::memcpy(&cell, b.data() + 32, 8);
  EXPECT_EQ(nx, 40U);
  EXPECT_EQ(ny, 20U);
  EXPECT_EQ(x0, -10);
  EXPECT_EQ(y0, -5);
  EXPECT_EQ(cell, 0.5);
  auto height = [&b](std::size_t i, std::size_t j) {
    float h = 0;
    std::memcpy(&h, b.data() + 40 + 4 * (j * 40 + i), 4);
    return h;
  };
  // Under the plunge (cell centre X 0.25, Y 0.25); the post filter rounds the turn at the bottom.
  EXPECT_NEAR(height(20, 10), -2, 1e-3);
  EXPECT_EQ(height(0, 0), 0);  // a corner of the stock: its top
  EXPECT_EQ(json::parse(machine_json(m))["load_target_pct"], m.adaptive.target_load_pct);
  EXPECT_EQ(control(c, "reset-stock", "").http_status, 200);

  runtime::Controller plain(default_machine_config(), o);
  EXPECT_EQ(plain.heightmap(), nullptr);
  EXPECT_EQ(control(plain, "reset-stock", "").http_status, 409);
}

}  // namespace
}  // namespace cncore::hmi
