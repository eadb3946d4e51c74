// LinuxCNC's own interpreter tests (../shared/testdata/linuxcnc-interp, CNCORE_SHARED_DIR) as
// the oracle: every case is run through the interpreter and its motion (STRAIGHT_TRAVERSE,
// STRAIGHT_FEED, ARC_FEED of the canonical listing, CanonPrinter) must match `expected` within
// 1e-4 program units, and its operator messages (MESSAGE: (msg,…) and (debug,…) comments with
// the parameters' values) word for word; a case that LinuxCNC rejects must fail with an InputError.
// Cases that need an INI file, Python or a plug-in are out of scope. The counts are printed; the
// cases listed in linuxcnc_interp_passing.txt must keep passing (the list grows as features land).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "config/tool_table.hpp"
#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;

struct Run {
  std::string program, tool_table;
  std::vector<std::string> subroutine_path;  // from the INI file's [RS274NGC] SUBROUTINE_PATH
};

struct Case {
  std::string name;  // relative folder, or bad/<file> and good/<file>
  fs::path dir;
  std::vector<Run> runs;
  fs::path expected;
  bool must_fail = false;
  bool in_scope = true;
  bool messages_only = false;     // test.sh keeps only the MESSAGE lines of the listing
  bool no_negative_zero = false;  // test.sh writes -0.0000… as 0.0000…
  std::string grep;               // test.sh keeps only the lines holding this text
};

std::string collapse_blanks(const std::string& s) {
  std::istringstream in(s);
  std::string word, out;
  while (in >> word) out += (out.empty() ? "" : " ") + word;
  return out;
}

std::vector<std::vector<double>> motion_lines(const std::string& text) {
  static const std::regex kCall(
      R"((STRAIGHT_TRAVERSE|STRAIGHT_FEED|ARC_FEED|RIGID_TAP)\(([^)]*)\))");
  std::vector<std::vector<double>> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kCall);
       it != std::sregex_iterator(); ++it) {
    std::vector<double> v;
    const std::string call = (*it)[1].str();
    v.push_back(call == "STRAIGHT_TRAVERSE" ? 0
                : call == "STRAIGHT_FEED"   ? 1
                : call == "ARC_FEED"        ? 2
                                            : 3);
    std::stringstream ss((*it)[2].str());
    std::string tok;
    while (std::getline(ss, tok, ',')) v.push_back(std::stod(tok));
    out.push_back(v);
  }
  return out;
}

// The MESSAGE texts of a canonical listing, blanks collapsed (the cases' test.sh pipe the
// listing through awk, which does the same).
std::vector<std::string> message_lines(const std::string& text) {
  static const std::regex kMessage(R"re(MESSAGE\("(.*)"\))re");
  std::vector<std::string> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kMessage);
       it != std::sregex_iterator(); ++it) {
    out.push_back(collapse_blanks((*it)[1].str()));
  }
  return out;
}

// The folders of an INI file's [RS274NGC] SUBROUTINE_PATH (':'-separated, relative to the
// case); none when the file sets anything else (a machine, Python, options cncore lacks).
std::optional<std::vector<std::string>> ini_subroutine_path(const fs::path& ini) {
  if (!fs::exists(ini)) return std::nullopt;
  std::istringstream in(read_text(ini.string()));
  std::string line;
  std::vector<std::string> dirs;
  while (std::getline(in, line)) {
    line = collapse_blanks(line);
    if (line.empty() || line[0] == '#' || line[0] == ';' || line == "[RS274NGC]") continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos || collapse_blanks(line.substr(0, eq)) != "SUBROUTINE_PATH") {
      return std::nullopt;
    }
    std::istringstream paths(collapse_blanks(line.substr(eq + 1)));
    std::string dir;
    while (std::getline(paths, dir, ':')) dirs.push_back((ini.parent_path() / dir).string());
  }
  return dirs;
}

// The rs274 invocations of a test.sh: "rs274 … -g PROGRAM … [-t TABLE]".
Case read_case(const fs::path& dir, const fs::path& root) {
  Case c;
  c.dir = dir;
  c.name = fs::relative(dir, root).string();
  c.expected = dir / "expected";
  const std::string sh = read_text((dir / "test.sh").string());
  c.must_fail = sh.find("! rs274") != std::string::npos;
  c.messages_only = sh.find("awk '/MESSAGE/") != std::string::npos;
  c.no_negative_zero = sh.find("s/-0\\.0000/0.0000/g") != std::string::npos;
  static const std::regex kGrep(R"(\| grep '([^']+)')");
  if (std::smatch m; std::regex_search(sh, m, kGrep)) c.grep = m[1].str();
  // Out of scope: a program the script writes itself.
  static const std::regex kWritesProgram(R"(>\s*[\w.-]+\.ngc)");
  if (std::regex_search(sh, kWritesProgram)) c.in_scope = false;
  if (sh.find("g++") != std::string::npos) c.in_scope = false;  // builds a program on rs274
  std::istringstream lines(sh);
  std::string line;
  while (std::getline(lines, line)) {
    const std::size_t at = line.find("rs274 ");
    if (at == std::string::npos || line.find("-lrs274") != std::string::npos) continue;
    std::istringstream words(line.substr(at + 6));
    std::string w;
    Run r;
    while (words >> w && w != "|" && w != ">" && w != "2>&1") {
      if (w == "-p" || w == "-n") c.in_scope = false;
      if (w == "-i") {
        words >> w;
        const auto dirs = ini_subroutine_path(dir / w);
        if (dirs) r.subroutine_path = *dirs;
        c.in_scope = c.in_scope && dirs.has_value();
      } else if (w == "-t") {
        words >> r.tool_table;
      } else if (w != "-g" && w[0] != '-' && w.find('$') == std::string::npos) {
        r.program = w;
      } else if (w.find('$') != std::string::npos) {
        c.in_scope = false;
      }
    }
    if (!r.program.empty()) c.runs.push_back(r);
  }
  if (c.runs.empty()) c.in_scope = false;
  return c;
}

// The cases' folder: CNCORE_LINUXCNC_INTERP_DIR names another copy of LinuxCNC's tests/interp
// (e.g. the half kept apart), measured the same way.
fs::path cases_root() {
  if (const char* dir = std::getenv("CNCORE_LINUXCNC_INTERP_DIR")) return dir;
  return fs::path(CNCORE_SHARED_DIR) / "testdata" / "linuxcnc-interp";
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  const fs::path root = cases_root();
  if (!fs::exists(root)) return cases;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const fs::path folder = fs::relative(e.path().parent_path(), root);
    if (folder == "bad" || folder == "good") continue;  // single programs, read below
    if (e.is_regular_file() && e.path().filename() == "test.sh") {
      cases.push_back(read_case(e.path().parent_path(), root));
    } else if (e.is_regular_file() && e.path().filename() == "expected" &&
               !fs::exists(e.path().parent_path() / "test.sh") &&
               fs::exists(e.path().parent_path() / "test.ngc")) {
      // LinuxCNC's runner runs `rs274 -g test.ngc` where a case has no test.sh.
      Case c;
      c.dir = e.path().parent_path();
      c.name = fs::relative(c.dir, root).string();
      c.expected = e.path();
      c.runs.push_back({"test.ngc", "", {}});
      // With a test.ini the runner gives rs274 that INI file (and its Python, if any).
      if (fs::exists(c.dir / "test.ini")) {
        const auto dirs = ini_subroutine_path(c.dir / "test.ini");
        c.in_scope = dirs.has_value();
        if (dirs) c.runs[0].subroutine_path = *dirs;
      }
      cases.push_back(c);
    }
  }
  for (const char* sub : {"bad", "good"}) {
    if (!fs::exists(root / sub)) continue;
    for (const auto& e : fs::directory_iterator(root / sub)) {
      if (e.path().extension() != ".ngc") continue;
      Case c;
      c.dir = root / sub;
      c.name = std::string(sub) + "/" + e.path().filename().string();
      c.runs.push_back({e.path().filename().string(), "", {}});
      c.must_fail = std::string(sub) == "bad";
      c.expected = e.path().string() + ".expected";
      cases.push_back(c);
    }
  }
  std::sort(cases.begin(), cases.end(),
            [](const Case& a, const Case& b) { return a.name < b.name; });
  return cases;
}

// rs274 has no machine: no travel limits, and the A B C axes exist. Without an INI file its
// offset parameters are in inches.
MachineConfig unbounded_machine() {
  MachineConfig m = test_machine();
  m.parameters_inch = true;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    m.axes[a].enabled = true;
    m.axes[a].rotary = a >= 3;
    m.axes[a].min_mm = a >= 3 ? 0 : -1e9;
    m.axes[a].max_mm = a >= 3 ? 0 : 1e9;
  }
  return m;
}

// rs274's tool table is in its machine units, inches; cncore's is in mm.
ToolTable inch_table(const std::string& path) {
  ToolTable t = read_tool_table(path);
  for (auto& [number, e] : t) {
    for (std::size_t a = 0; a < 3; ++a) e.offset_mm[a] *= 25.4;
    e.diameter_mm *= 25.4;
  }
  return t;
}

// A case whose test.sh keeps only the lines holding `text`: those lines, in order, the same.
std::string compare_grepped(const std::string& text, const std::string& want_listing,
                            const std::string& got_listing) {
  auto lines = [&](const std::string& listing) {
    std::vector<std::string> out;
    std::istringstream in(listing);
    std::string line;
    while (std::getline(in, line)) {
      line = collapse_blanks(line);
      if (line.starts_with("N..... ")) line.erase(0, 7);
      if (line.find(text) != std::string::npos) out.push_back(line);
    }
    return out;
  };
  const auto want = lines(want_listing), got = lines(got_listing);
  for (std::size_t i = 0; i < std::min(want.size(), got.size()); ++i) {
    if (want[i] != got[i]) return "\"" + got[i] + "\", LinuxCNC \"" + want[i] + "\"";
  }
  if (want.size() != got.size()) {
    return std::to_string(got.size()) + " lines, LinuxCNC " + std::to_string(want.size());
  }
  return {};
}

// Runs one case; an empty result means it passed, else why it did not.
std::string run_case(const Case& c) {
  const MachineConfig m = unbounded_machine();
  std::string canon;
  try {
    for (const Run& r : c.runs) {
      Options o;
      if (!r.tool_table.empty()) o.tools = inch_table((c.dir / r.tool_table).string());
      o.subroutine_path = r.subroutine_path;
      o.zero_length_moves = true;
      o.on_message = [&](const std::string& text) { canon += "MESSAGE(\"" + text + "\")\n"; };
      Interpreter in((c.dir / r.program).string(), m, o);
      CanonPrinter p;
      Block b;
      while (in.next(b)) canon += p.print(b, in.canon_frame());
    }
  } catch (const InputError& e) {
    if (c.must_fail) return {};
    return "error: " + e.formatted();
  }
  if (c.must_fail) return "accepted a program that LinuxCNC rejects";
  if (!fs::exists(c.expected)) return "no expected output";
  if (!c.grep.empty()) return compare_grepped(c.grep, read_text(c.expected.string()), canon);
  const auto want = motion_lines(read_text(c.expected.string()));
  const auto got = c.messages_only ? want : motion_lines(canon);
  for (std::size_t i = 0; i < std::min(want.size(), got.size()); ++i) {
    bool same = want[i].size() == got[i].size();
    for (std::size_t k = 0; same && k < want[i].size(); ++k) {
      same = std::fabs(want[i][k] - got[i][k]) <= 1e-4 + 1e-9;
    }
    if (!same) return "motion " + std::to_string(i + 1) + " differs";
  }
  if (want.size() != got.size()) {
    return std::to_string(got.size()) + " motions, LinuxCNC " + std::to_string(want.size());
  }
  const auto want_msg = message_lines(read_text(c.expected.string()));
  auto got_msg = message_lines(canon);
  for (std::string& text : got_msg) {
    for (std::size_t at = 0;
         c.no_negative_zero && (at = text.find("-0.0000", at)) != std::string::npos;)
      text.erase(at, 1);
  }
  for (std::size_t i = 0; i < std::min(want_msg.size(), got_msg.size()); ++i) {
    if (want_msg[i] != got_msg[i]) {
      return "message " + std::to_string(i + 1) + " \"" + got_msg[i] + "\", LinuxCNC \"" +
             want_msg[i] + "\"";
    }
  }
  if (want_msg.size() != got_msg.size()) {
    return std::to_string(got_msg.size()) + " messages, LinuxCNC " +
           std::to_string(want_msg.size());
  }
  return {};
}

std::set<std::string> passing_list() {
  std::set<std::string> names;
  std::istringstream in(
      read_text(std::string(CNCORE_INTERP_TEST_DIR) + "/linuxcnc_interp_passing.txt"));
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') names.insert(line);
  }
  return names;
}

TEST(LinuxCncInterp, ListedCasesKeepPassing) {
  const std::vector<Case> cases = all_cases();
  if (cases.empty()) GTEST_SKIP() << "LinuxCNC interpreter tests not found under " << cases_root();
  const bool shared_copy = std::getenv("CNCORE_LINUXCNC_INTERP_DIR") == nullptr;
  const std::set<std::string> listed = passing_list();
  std::size_t pass = 0, fail = 0, out_of_scope = 0;
  for (const Case& c : cases) {
    if (!c.in_scope) {
      ++out_of_scope;
      std::printf("  %-55s out of scope (INI, Python, plug-in or generated program)\n",
                  c.name.c_str());
      continue;
    }
    const std::string why = run_case(c);
    if (why.empty()) {
      ++pass;
    } else {
      ++fail;
    }
    std::printf("  %-55s %s\n", c.name.c_str(), why.empty() ? "pass" : ("FAIL " + why).c_str());
    if (listed.contains(c.name)) {
      EXPECT_EQ(why, "") << c.name;
    }
  }
  std::printf("linuxcnc-interp: %zu pass, %zu fail, %zu out of scope\n", pass, fail, out_of_scope);
  for (const std::string& name : listed) {
    if (!shared_copy) break;  // the list names the cases of ../shared's copy
    EXPECT_TRUE(
        std::any_of(cases.begin(), cases.end(), [&](const Case& c) { return c.name == name; }))
        << name << " is listed but not found";
  }
}

}  // namespace
}  // namespace cncore::interp::test
