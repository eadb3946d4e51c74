// The HTML report opened in a real browser (headless Chromium, Debian package `chromium`, which
// `make` installs): the page runs without console errors, the charts and the top view are drawn
// (canvases with ink on them), and the title and summary values are those of the run.
// Skips only when no Chromium is installed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

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
  // uPlot draws each chart on a canvas, plus the top view: all three with ink on them.
  EXPECT_EQ(attr(dom, "data-canvases"), "3");
  EXPECT_EQ(attr(dom, "data-inked"), "3");
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
  // The table of slow lines has ten rows and the override column (the run had --override).
  EXPECT_NE(dom.find("override (%)"), std::string::npos);
  std::size_t rows = 0;
  for (std::size_t p = dom.find("<tr><td>"); p != std::string::npos;
       p = dom.find("<tr><td>", p + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, 10u);
}

// The table report (`cncore table … --report`): four charts (axis speeds, accelerations,
// reference with the M codes, positions), drawn without errors.
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
  EXPECT_EQ(attr(dom, "data-canvases"), "4");
  EXPECT_EQ(attr(dom, "data-inked"), "4");
  EXPECT_NE(dom.find("<title>cncore table report: fig6-x.tbl, fig6-z.tbl</title>"),
            std::string::npos);
  EXPECT_NE(dom.find("<td>M11</td>"), std::string::npos);
  EXPECT_NE(dom.find("<td>M12</td>"), std::string::npos);
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
