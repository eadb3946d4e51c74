#include "app/estimate_output.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "io/report_page.hpp"

namespace cncore::app::estimate {
namespace {

// RFC 4180: a field with a comma, quote or line break is quoted, quotes doubled.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string escape_html(const std::string& s) {
  return io::page::html_escape(s);
}

std::string line_range(const SlowLine& l) {
  return l.last_line > l.line ? fmt::format("{}-{}", l.line, l.last_line)
                              : fmt::format("{}", l.line);
}

// "LINE:LOST_S" for each slow line, worst first, separated by ';'.
std::string slow_lines_text(const std::vector<SlowLine>& lines) {
  std::string o;
  for (const SlowLine& l : lines) {
    if (!o.empty()) o += ';';
    o += fmt::format("{}:{:.3f}", line_range(l), l.lost_s);
  }
  return o;
}

}  // namespace

bool read_summary_json(const std::string& text, ProgramResult& r) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("cycle_time_s")) return false;
  r.cycle_time_s = j.value("cycle_time_s", 0.0);
  r.path_length_mm = j.value("path_length_mm", 0.0);
  r.blocks = j.value("blocks", std::uint64_t{0});
  r.cycles = j.value("cycles", std::uint64_t{0});
  r.slowest.clear();
  if (j.contains("slowest_spots") && j["slowest_spots"].is_array()) {
    for (const auto& s : j["slowest_spots"]) {
      SlowLine l;
      l.line = s.value("line", 0U);
      l.last_line = s.value("last_line", l.line);
      l.lost_s = s.value("lost_s", 0.0);
      l.time_s = s.value("time_s", 0.0);
      r.slowest.push_back(l);
    }
  }
  // The whole program's loss (the summary shares every cycle's among the blocks it passed), not
  // only the slowest lines'.
  r.time_lost_s = j.value("time_lost_s", 0.0);
  return true;
}

std::string results_csv(const std::vector<ProgramResult>& results) {
  std::string o =
      "program,status,cycle_time_s,path_length_mm,blocks,cycles,time_lost_s,slowest_lines,error\n";
  for (const ProgramResult& r : results) {
    if (r.ok) {
      o += fmt::format("{},ok,{:.6f},{:.6f},{},{},{:.6f},{},\n", csv_field(r.program),
                       r.cycle_time_s, r.path_length_mm, r.blocks, r.cycles, r.time_lost_s,
                       csv_field(slow_lines_text(r.slowest)));
    } else {
      o += fmt::format("{},error,,,,,,,{}\n", csv_field(r.program), csv_field(r.error));
    }
  }
  return o;
}

std::string results_html(const std::vector<ProgramResult>& results, const std::string& machine,
                         double wall_s, unsigned jobs) {
  std::vector<const ProgramResult*> ranked;
  ranked.reserve(results.size());
  for (const ProgramResult& r : results) ranked.push_back(&r);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const ProgramResult* a, const ProgramResult* b) {
                     if (a->ok != b->ok) return a->ok;
                     return a->cycle_time_s > b->cycle_time_s;
                   });
  double total_s = 0, longest_s = 0;
  std::size_t failed = 0;
  for (const ProgramResult& r : results) {
    total_s += r.ok ? r.cycle_time_s : 0;
    longest_s = std::max(longest_s, r.ok ? r.cycle_time_s : 0);
    failed += r.ok ? 0 : 1;
  }
  std::string o =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
      "<title>cncore estimate</title>\n<style>\n"
      "body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse}\n"
      "td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:right}\n"
      "td.p,th.p{text-align:left}td.e{text-align:left;color:#b00}\n"
      ".bar{background:#4a7ebb;height:10px}\n</style></head><body>\n"
      "<h1>Cycle-time estimate</h1>\n";
  o += fmt::format(
      "<p>{} programs on {}: {} ok, {} failed. Total cycle time {:.3f} s ({:.2f} h). "
      "Estimated in {:.1f} s of wall time with {} worker processes.</p>\n",
      results.size(), escape_html(machine), results.size() - failed, failed, total_s,
      total_s / 3600, wall_s, jobs);
  o += "<table id=\"ranking\">\n<tr><th>rank</th><th class=\"p\">program</th><th>cycle time "
       "s</th><th class=\"p\"></th><th>path mm</th><th>blocks</th><th>time lost s</th>"
       "<th class=\"p\">slowest lines (line: s lost)</th></tr>\n";
  std::size_t rank = 0;
  for (const ProgramResult* r : ranked) {
    ++rank;
    if (!r->ok) {
      o += fmt::format(
          "<tr class=\"failed\"><td>{}</td><td class=\"p\">{}</td><td class=\"e\" "
          "colspan=\"6\">{}</td></tr>\n",
          rank, escape_html(r->program), escape_html(r->error));
      continue;
    }
    const double width_pct = longest_s > 0 ? 100 * r->cycle_time_s / longest_s : 0;
    std::string slow;
    for (const SlowLine& l : r->slowest) {
      slow += fmt::format("{}{}: {:.3f}", slow.empty() ? "" : ", ", line_range(l), l.lost_s);
    }
    o += fmt::format(
        "<tr class=\"ok\"><td>{}</td><td class=\"p\">{}</td><td>{:.3f}</td>"
        "<td class=\"p\" style=\"width:12em\"><div class=\"bar\" style=\"width:{:.1f}%\"></div>"
        "</td><td>{:.1f}</td><td>{}</td><td>{:.3f}</td><td class=\"p\">{}</td></tr>\n",
        rank, escape_html(r->program), r->cycle_time_s, width_pct, r->path_length_mm, r->blocks,
        r->time_lost_s, slow);
  }
  o += "</table>\n<p>Cycle times are those of <code>cncore run</code> on each program; time lost "
       "is against the programmed feed on the slowest lines.</p>\n</body></html>\n";
  return o;
}

}  // namespace cncore::app::estimate
