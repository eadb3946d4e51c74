// The HTML report opened in a real browser (headless Chromium, Debian package `chromium`, which
// `make` installs): the page runs without console errors, the charts and the top view are drawn
// (canvases with ink on them), and the title and summary values are those of the run.
// Skips only when no Chromium is installed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "files.hpp"

namespace {

namespace fs = std::filesystem;

using cncore::testing::slurp;
constexpr auto quote = cncore::testing::shell_quote;

int shell(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// CHROMIUM from the environment, else the usual names on PATH.
std::string find_chromium() {
  if (const char* env = std::getenv("CHROMIUM"); env != nullptr && *env != '\0') return env;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    for (const char* name :
         {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"}) {
      const fs::path p = fs::path(dir) / name;
      if (::access(p.c_str(), X_OK) == 0) return p.string();
    }
  }
  return {};
}

class ReportBrowser : public ::testing::Test {
 protected:
  void SetUp() override {
    chromium_ = find_chromium();
    if (chromium_.empty()) {
      GTEST_SKIP() << "no Chromium installed (Debian: apt-get install chromium; `make test` "
                      "installs it)";
    }
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CNCORE_TEST_TMP_DIR) / "browser" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  // Loads the page in headless Chromium; returns the DOM after the scripts ran (virtual time lets
  // the timers fire) and leaves the browser's log in log_.
  std::string dom_of(const fs::path& html) {
    const fs::path out = dir_ / "dom.html", log = dir_ / "chromium.log";
    const std::string cmd =
        "timeout 120 " + quote(chromium_) +
        " --headless --no-sandbox --disable-gpu --no-first-run --disable-extensions"
        " --user-data-dir=" +
        quote((dir_ / "profile").string()) +
        " --enable-logging=stderr --v=0 --virtual-time-budget=10000 --dump-dom " +
        quote("file://" + fs::absolute(html).string()) + " > " + quote(out.string()) + " 2> " +
        quote(log.string());
    EXPECT_EQ(shell(cmd), 0) << cmd << "\n" << slurp(log);
    log_ = slurp(log);
    return slurp(out);
  }

  // A picture of the page as a reader sees it, 1200 px wide, into dir_ (and into
  // $CNCORE_SCREENSHOT_DIR when set, e.g. docs/images to refresh the docs' pictures).
  fs::path screenshot(const fs::path& html, const std::string& name, int height) {
    const fs::path png = dir_ / name;
    const std::string cmd =
        "timeout 120 " + quote(chromium_) +
        " --headless --no-sandbox --disable-gpu --no-first-run --disable-extensions"
        " --hide-scrollbars --force-device-scale-factor=1 --user-data-dir=" +
        quote((dir_ / "profile").string()) + " --window-size=1200," + std::to_string(height) +
        " --virtual-time-budget=10000 --screenshot=" + quote(png.string()) + " " +
        quote("file://" + fs::absolute(html).string()) + " > /dev/null 2>&1";
    EXPECT_EQ(shell(cmd), 0) << cmd;
    const std::string bytes = slurp(png);
    EXPECT_GT(bytes.size(), 20000u) << png;  // a page with charts, not a blank one
    EXPECT_EQ(bytes.substr(0, 4), "\x89PNG") << png;
    if (const char* out = std::getenv("CNCORE_SCREENSHOT_DIR"); out != nullptr && *out != 0) {
      fs::copy_file(png, fs::path(out) / name, fs::copy_options::overwrite_existing);
    }
    return png;
  }

  // Console messages of the page at level error, and uncaught exceptions, from the browser log
  // ("…:CONSOLE(line)] "message", source: …"). The browser's own complaints (D-Bus, GPU) are not
  // the page's and do not count.
  std::vector<std::string> console_errors() const {
    std::vector<std::string> errors;
    std::istringstream in(log_);
    std::string line;
    while (std::getline(in, line)) {
      if (line.find("CONSOLE") == std::string::npos) continue;
      if (line.find("ERROR:CONSOLE") != std::string::npos ||
          line.find("Uncaught") != std::string::npos) {
        errors.push_back(line);
      }
    }
    return errors;
  }

  static std::string attr(const std::string& dom, const std::string& name) {
    const std::regex re("id=\"cncore-status\"[^>]*\\b" + name + "=\"([^\"]*)\"");
    std::smatch m;
    return std::regex_search(dom, m, re) ? m[1].str() : std::string("(missing)");
  }
  static double summary_value(const std::string& dom, const std::string& key) {
    const std::regex re("id=\"s-" + key + "\" data-value=\"([^\"]*)\"");
    std::smatch m;
    return std::regex_search(dom, m, re) ? std::stod(m[1].str()) : -1;
  }

  std::string chromium_, log_;
  fs::path dir_;
};

TEST_F(ReportBrowser, ChartsRenderWithoutErrorsAndShowTheRunsFigures) {
  const fs::path html = dir_ / "pocket.html", json = dir_ / "pocket.json";
  const std::string run = quote(CNCORE_BIN) + " run " +
                          quote(std::string(CNCORE_SOURCE_DIR) + "/examples/pocket-with-arcs.ngc") +
                          " --override 150 --report " + quote(html.string()) + " --summary " +
                          quote(json.string()) + " > /dev/null";
  ASSERT_EQ(shell(run), 0) << run;
  const std::string dom = dom_of(html);
  ASSERT_FALSE(dom.empty()) << log_;

  EXPECT_TRUE(console_errors().empty()) << console_errors().front();
  EXPECT_EQ(attr(dom, "data-errors"), "0") << dom.substr(0, 2000);
  EXPECT_EQ(attr(dom, "data-rendered"), "ok");
  EXPECT_EQ(attr(dom, "data-charts"), "2");  // speed and acceleration; no correction or load
  // uPlot draws each chart on a canvas, plus the bars of the time lost and the top, front and
  // side views: all six with ink on them.
  EXPECT_EQ(attr(dom, "data-canvases"), "6");
  EXPECT_EQ(attr(dom, "data-inked"), "6");
  EXPECT_NE(dom.find("class=\"uplot"), std::string::npos);
  EXPECT_NE(dom.find("<title>cncore report: pocket-with-arcs.ngc</title>"), std::string::npos);

  const auto j = nlohmann::json::parse(slurp(json));
  for (const char* key : {"cycle_time_s", "path_length_mm", "max_feed_mm_min",
                          "max_tangential_accel_mm_s2", "max_contour_error_mm"}) {
    const double want = j.at(key).get<double>();
    EXPECT_NEAR(summary_value(dom, key), want, 1e-6 * std::max(1.0, want)) << key;
  }
  EXPECT_EQ(summary_value(dom, "blocks"), j.at("blocks").get<double>());
  EXPECT_EQ(summary_value(dom, "cycles"), j.at("cycles").get<double>());
  EXPECT_NEAR(summary_value(dom, "time_lost_s"), j.at("time_lost_s").get<double>(), 1e-9);
  // The table of slow cutting lines has ten rows and the override column (the run had
  // --override).
  EXPECT_NE(dom.find("override (%)"), std::string::npos);
  const std::size_t table = dom.find("id=\"slowest\"");
  ASSERT_NE(table, std::string::npos);
  const std::size_t end = dom.find("</table>", table);
  std::size_t rows = 0;
  for (std::size_t p = dom.find("<tr><td>", table); p < end; p = dom.find("<tr><td>", p + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, 10u);
}

// The table report (`cncore table … --report`): four charts (axis speeds, accelerations,
// reference with the M codes, positions) and the path in the X–Z plane, drawn without errors.
TEST_F(ReportBrowser, TableReportChartsRenderWithoutErrors) {
  const fs::path html = dir_ / "fig6.html";
  const std::string tables = std::string(CNCORE_SOURCE_DIR) + "/examples/tables/";
  const std::string run =
      quote(CNCORE_BIN) + " table " + quote(tables + "fig6-x.tbl") + " " +
      quote(tables + "fig6-z.tbl") + " --machine " + quote(tables + "lathe.toml") +
      " --var 501=0 --var 502=0 --var 503=0 --report " + quote(html.string()) + " > /dev/null 2>&1";
  ASSERT_EQ(shell(run), 0) << run;
  const std::string dom = dom_of(html);
  ASSERT_FALSE(dom.empty()) << log_;
  EXPECT_TRUE(console_errors().empty()) << console_errors().front();
  EXPECT_EQ(attr(dom, "data-errors"), "0") << dom.substr(0, 2000);
  EXPECT_EQ(attr(dom, "data-rendered"), "ok");
  EXPECT_EQ(attr(dom, "data-charts"), "4");
  // The four charts and the path in the X–Z plane.
  EXPECT_EQ(attr(dom, "data-canvases"), "5");
  EXPECT_EQ(attr(dom, "data-inked"), "5");
  EXPECT_NE(dom.find("<title>cncore table report: fig6-x.tbl, fig6-z.tbl</title>"),
            std::string::npos);
  EXPECT_NE(dom.find("<td>M11</td>"), std::string::npos);
  EXPECT_NE(dom.find("<td>M12</td>"), std::string::npos);
}

// The pictures in docs/reports.md: a real part (enclosure.nc from ../shared; skipped without
// it), a 3D surface raster and a table run, each rendered without errors.
TEST_F(ReportBrowser, ScreenshotsOfAPartASurfaceAndATable) {
  std::vector<std::pair<std::string, std::string>> runs;  // picture, cncore arguments
  const fs::path enclosure = fs::path(CNCORE_SHARED_DIR) / "testdata/gcode/ugs/enclosure.nc";
  const bool shared = fs::exists(enclosure);
  if (shared) runs.emplace_back("report-enclosure.png", "run " + quote(enclosure.string()));
  // A dome z = 4·(1 − r²/R²) in raster lines of 1 mm steps along X, rows 2 mm apart, F2000.
  const fs::path surface = dir_ / "dome.ngc";
  {
    std::ofstream out(surface);
    out << "G21 G90 G17\nG0 Z5\nG0 X-20 Y-20\n";
    for (int row = 0; row <= 20; ++row) {
      const double y = -20 + 2.0 * row;
      for (int k = 0; k <= 40; ++k) {
        const double x = row % 2 == 0 ? -20.0 + k : 20.0 - k;
        const double z = std::max(0.0, 4 * (1 - (x * x + y * y) / 400)) - 4;
        out << "G1 X" << x << " Y" << y << " Z" << z << (k == 0 && row == 0 ? " F2000" : "")
            << "\n";
      }
    }
    out << "G0 Z5\nM2\n";
  }
  runs.emplace_back("report-surface.png", "run " + quote(surface.string()));
  const std::string tables = std::string(CNCORE_SOURCE_DIR) + "/examples/tables/";
  runs.emplace_back("report-table.png", "table " + quote(tables + "fig6-x.tbl") + " " +
                                            quote(tables + "fig6-z.tbl") + " --machine " +
                                            quote(tables + "lathe.toml") +
                                            " --var 501=0 --var 502=0 --var 503=0");
  // The cutting simulation's height map in the page (examples/cutting: a pocket in a stock).
  const std::string cutting = std::string(CNCORE_SOURCE_DIR) + "/examples/cutting/";
  runs.emplace_back("report-cutting.png", "run " + quote(cutting + "pocket.ngc") + " --machine " +
                                              quote(cutting + "mill.toml"));
  for (const auto& [picture, args] : runs) {
    SCOPED_TRACE(picture);
    const fs::path html = dir_ / (picture + ".html");
    const std::string run =
        quote(CNCORE_BIN) + " " + args + " --report " + quote(html.string()) + " > /dev/null 2>&1";
    ASSERT_EQ(shell(run), 0) << run;
    const std::string dom = dom_of(html);
    EXPECT_EQ(attr(dom, "data-errors"), "0") << dom.substr(0, 2000);
    EXPECT_EQ(attr(dom, "data-rendered"), "ok");
    if (picture == "report-cutting.png") {
      EXPECT_NE(dom.find("id=\"heightmap\""), std::string::npos);
    }
    screenshot(html, picture, 3000);
  }
  if (!shared) GTEST_SKIP() << enclosure << " absent (../shared): its picture not taken";
}

// The check above can fail: a page whose chart code throws is caught both in the page and in the
// browser log.
TEST_F(ReportBrowser, BrokenPageIsDetected) {
  const fs::path html = dir_ / "ok.html";
  const std::string run =
      quote(CNCORE_BIN) + " run " +
      quote(std::string(CNCORE_SOURCE_DIR) + "/examples/seed-line-arc-line.ngc") + " --report " +
      quote(html.string()) + " > /dev/null";
  ASSERT_EQ(shell(run), 0) << run;
  std::string page = slurp(html);
  const std::size_t at = page.find("new uPlot(");
  ASSERT_NE(at, std::string::npos);
  page.replace(at, 10, "new uPlotMissing(");
  const fs::path broken = dir_ / "broken.html";
  std::ofstream(broken) << page;
  const std::string dom = dom_of(broken);
  EXPECT_FALSE(console_errors().empty()) << log_;
  EXPECT_NE(attr(dom, "data-rendered"), "ok");
}

}  // namespace
