// The HTML report of table operation (`cncore table … --report`): the observer keeps the extremes
// of every axis through decimation at flat memory and marks the M codes; the page carries the
// run's figures (values checked by hand: 0.1 mm per 1 ms cycle is 100 mm/s = 6000 mm/min; a stop
// from 100 mm/s within one 1 ms cycle is 100 000 mm/s²).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "files.hpp"
#include "io/report_table.hpp"
#include "io/summary.hpp"

namespace cncore::io {
namespace {

namespace fs = std::filesystem;
using cncore::testing::slurp;
using cncore::testing::write_file;
constexpr auto quote = cncore::testing::shell_quote;

constexpr std::uint32_t kX = 1U << 0, kZ = 1U << 2;

// X from 0 to 100 mm in 1000 cycles of 1 ms, then still for 500 cycles; Z still; the reference
// is the time in ms. M11 fires at cycle 1000 (t = 1 s).
struct Synthetic {
  MachineConfig machine = default_machine_config();
  TableReportObserver report{machine, kX | kZ};
  SummaryObserver summary{machine, "table"};
  Synthetic() {
    for (int k = 0; k <= 1500; ++k) {
      motion::Sample s;
      s.t_s = k * 1e-3;
      s.ref = k;
      s.position[0] = 0.1 * std::min(k, 1000);
      s.path_position = s.position;
      if (k == 1000) report.add_m_code(s.t_s, 0, 3, 11, s.ref);
      report.on_sample(s);
      summary.on_sample(s);
    }
    report.on_finish();
    summary.on_finish();
  }
};

TEST(TableReportObserver, AxisSpeedAccelerationAndMCodeOfAKnownMove) {
  const Synthetic r;
  EXPECT_EQ(r.report.axis_mask(), kX | kZ);
  EXPECT_EQ(r.report.samples(), 1501u);
  EXPECT_EQ(r.report.m_code_count(), 1u);
  double vx = 0, ax = 0, vz = 0, pos_max = -1;
  std::uint32_t m_codes = 0;
  double m_t = -1;
  for (const TableReportBucket& b : r.report.buckets()) {
    vx = std::max(vx, b.speed[0].max);
    ax = std::max(ax, b.accel[0].max);
    vz = std::max(vz, b.speed[2].max);
    pos_max = std::max(pos_max, b.position[0].max);
    EXPECT_TRUE(std::isnan(b.speed[1].max)) << "Y is not charted";
    if (b.m_codes > 0) m_t = b.t_first_s;
    m_codes += b.m_codes;
  }
  EXPECT_NEAR(vx, 6000, 1e-6);
  EXPECT_NEAR(ax, 100000, 1e-3);
  EXPECT_EQ(vz, 0);
  EXPECT_NEAR(pos_max, 100, 1e-12);
  EXPECT_EQ(m_codes, 1u);
  EXPECT_NEAR(m_t, 1.0, 1e-9);
  // The same finite differences as the summary: the peaks agree exactly.
  EXPECT_EQ(vx, r.summary.summary().max_axis_speed_mm_min[0]);
  EXPECT_EQ(ax, r.summary.summary().max_axis_accel_mm_s2[0]);
  ASSERT_EQ(r.report.events().size(), 1u);
  EXPECT_EQ(r.report.events()[0].code, 11);
  EXPECT_EQ(r.report.events()[0].ref, 1000);
}

TEST(TableReportObserver, OneMillionCyclesKeepTheSpikeAndTheMemoryIsFlat) {
  // X at 100 mm/s except one cycle that moves 0.05 mm further (150 mm/s = 9000 mm/min).
  const MachineConfig m = default_machine_config();
  TableReportObserver r(m, kX, TableReportOptions{256, 10});
  constexpr std::uint64_t kSpike = 777'777, kSamples = 1'000'000;
  std::size_t mem_at_100k = 0;
  for (std::uint64_t k = 0; k < kSamples; ++k) {
    motion::Sample s;
    s.t_s = static_cast<double>(k) * 1e-3;
    s.ref = s.t_s * 1000;
    s.position[0] = 0.1 * static_cast<double>(k) + (k >= kSpike ? 0.05 : 0.0);
    if (k % 1000 == 0) r.add_m_code(s.t_s, 0, 1, 7, s.ref);
    r.on_sample(s);
    if (k == 100'000) mem_at_100k = r.memory_bytes();
  }
  EXPECT_LE(r.buckets().size(), 512u);
  EXPECT_EQ(r.memory_bytes(), mem_at_100k) << "memory grows with the run";
  EXPECT_EQ(r.m_code_count(), 1000u);
  EXPECT_EQ(r.events().size(), 10u) << "the listed M codes are bounded";
  double vmax = 0, vmin = 1e9;
  bool found = false;
  std::uint64_t counted = 0, marked = 0;
  for (const TableReportBucket& b : r.buckets()) {
    vmax = std::max(vmax, b.speed[0].max);
    if (b.t_first_s > 0.01) vmin = std::min(vmin, b.speed[0].min);
    if (b.t_first_s <= 777.777 && b.t_last_s >= 777.777) found = b.speed[0].max > 8999;
    counted += b.samples;
    marked += b.m_codes;
  }
  EXPECT_EQ(counted, kSamples);
  EXPECT_EQ(marked, 1000u);
  EXPECT_NEAR(vmax, 9000, 1e-3);
  EXPECT_NEAR(vmin, 6000, 1e-3);
  EXPECT_TRUE(found);
}

// The page's data script as JSON.
nlohmann::json page_data(const std::string& html) {
  const std::string start = "window.CNCORE_DATA=";
  const std::size_t a = html.find(start);
  const std::size_t b = html.find(";</script>", a);
  if (a == std::string::npos || b == std::string::npos) return nullptr;
  return nlohmann::json::parse(html.substr(a + start.size(), b - a - start.size()));
}

double summary_value(const std::string& html, const std::string& key) {
  const std::regex re("id=\"s-" + key + "\" data-value=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(html, m, re) ? std::stod(m[1].str()) : -1;
}

TEST(TableReportHtml, PageCarriesTheChartsDataSummaryAndMCodes) {
  const Synthetic r;
  TableReportInput in;
  in.tables = {"dir/cam<1>.tbl"};
  in.ref_name = "time";
  in.ref_unit = "ms";
  in.end_ref = 1500;
  const std::string html = render_table_report_html(r.report, r.summary.summary(), r.machine, in);
  EXPECT_NE(html.find("<title>cncore table report: cam&lt;1&gt;.tbl</title>"), std::string::npos);
  EXPECT_EQ(html.find("cam<1>"), std::string::npos) << "file names are escaped";
  for (const char* id : {"speed-chart", "accel-chart", "ref-chart", "pos-chart", "m-codes"}) {
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  }
  EXPECT_NEAR(summary_value(html, "max_speed_X"), 6000, 1e-6);
  EXPECT_NEAR(summary_value(html, "max_accel_X"), 100000, 1e-3);
  EXPECT_EQ(summary_value(html, "max_speed_Y"), -1) << "Y is not charted";
  EXPECT_EQ(summary_value(html, "m_codes"), 1);
  EXPECT_EQ(summary_value(html, "cycles"), 1501);
  EXPECT_NE(html.find("<td>M11</td><td>cam&lt;1&gt;.tbl</td><td class=\"num\">3</td>"),
            std::string::npos);

  const nlohmann::json d = page_data(html);
  ASSERT_TRUE(d.is_object());
  const std::size_t n = d.at("t").size();
  EXPECT_EQ(n, 2 * r.report.buckets().size());
  ASSERT_EQ(d.at("axes").size(), 2u);
  EXPECT_EQ(d["axes"][0]["name"], "X");
  EXPECT_EQ(d["axes"][1]["name"], "Z");
  EXPECT_EQ(d["axes"][0]["speed_limit"], r.machine.axes[0].max_speed_mm_min);
  EXPECT_EQ(d["axes"][0]["accel_limit"], r.machine.axes[0].max_accel_mm_s2);
  double vmax = 0, ref_max = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(d["axes"][0]["speed"].size(), n);
    if (d["axes"][0]["speed"][i].is_number()) {
      vmax = std::max(vmax, d["axes"][0]["speed"][i].get<double>());
    }
    ref_max = std::max(ref_max, d["ref"][i].get<double>());
  }
  EXPECT_NEAR(vmax, 6000, 1e-3);  // 6 significant digits on the page
  EXPECT_EQ(ref_max, 1500);
  // One M marker, at the reference value where M11 fired.
  int markers = 0;
  for (const auto& v : d.at("m")) {
    if (!v.is_null()) {
      ++markers;
      EXPECT_EQ(v.get<double>(), 1000);
    }
  }
  EXPECT_EQ(markers, 1);
}

int shell(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// Through the binary: the page's figures are the summary's, and by hand.
TEST(TableReportCli, ReportOfATableRunMatchesItsSummary) {
  const fs::path dir = fs::path(CNCORE_TEST_TMP_DIR) / "table_report";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path tbl = dir / "move.tbl", html = dir / "move.html", json = dir / "move.json",
                 out = dir / "stdout.txt";
  // X 0 → 100 mm between 1000 and 2000 ms: 100 mm/s = 6000 mm/min; M11 at 1 s, M12 at 2 s.
  write_file(tbl, "REF TIME\nAXES X\nL0 X0\nL1000 X0 M11\nL2000 X100 M12\n");
  // X stiff enough for the linear distribution's velocity steps of 100 mm/s within 1 ms.
  const fs::path machine = dir / "stiff.toml";
  write_file(machine, "[axes.x]\nmax_accel_mm_s2 = 150000\n");
  const std::string cmd = quote(CNCORE_BIN) + " table " + quote(tbl.string()) + " --machine " +
                          quote(machine.string()) + " --report " + quote(html.string()) +
                          " --summary " + quote(json.string()) + " > " + quote(out.string()) +
                          " 2>&1";
  ASSERT_EQ(shell(cmd), 0) << cmd << "\n" << slurp(out);
  EXPECT_NE(slurp(out).find("report        " + html.string()), std::string::npos) << slurp(out);
  const std::string page = slurp(html);
  const auto j = nlohmann::json::parse(slurp(json));
  EXPECT_NEAR(summary_value(page, "cycle_time_s"), j.at("cycle_time_s").get<double>(), 1e-9);
  EXPECT_EQ(summary_value(page, "cycles"), j.at("cycles").get<double>());
  const double vx = j.at("max_axis_speed_mm_min").at("x").get<double>();
  EXPECT_NEAR(summary_value(page, "max_speed_X"), vx, 1e-6 * vx);
  EXPECT_NEAR(vx, 6000, 1e-6);
  EXPECT_NEAR(summary_value(page, "cycle_time_s"), 2.0, 1e-9);
  EXPECT_EQ(summary_value(page, "m_codes"), 2);
  EXPECT_NE(page.find("<td class=\"num\">1.000</td><td>M11</td>"), std::string::npos);
  EXPECT_NE(page.find("<td class=\"num\">2.000</td><td>M12</td>"), std::string::npos);
  EXPECT_NE(page.find("time 0 … 2000 ms"), std::string::npos);

  // An unwritable report path fails before the run and leaves nothing.
  const fs::path bad = dir / "missing-dir" / "r.html";
  EXPECT_EQ(
      shell(quote(CNCORE_BIN) + " table " + quote(tbl.string()) + " --machine " +
            quote(machine.string()) + " --report " + quote(bad.string()) + " > /dev/null 2>&1"),
      1);
  EXPECT_FALSE(fs::exists(bad));
}

}  // namespace
}  // namespace cncore::io
