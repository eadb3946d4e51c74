#include "app/estimate_output.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <nlohmann/json.hpp>

#include "io/report.hpp"
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

std::string cause_key(std::size_t i) {
  return io::loss_cause_key(static_cast<io::LossCause>(i));
}

// Bar colours of the causes, in the order of io::LossCause.
constexpr std::array<const char*, io::kLossCauses> kCauseColour{
    "#d1495b", "#edae49", "#8d6cab", "#00798c", "#4a7ebb", "#66a182", "#999999"};

// The causes of one program as a stacked bar (width relative to the batch's largest loss) and
// its two largest causes in words.
std::string causes_cell(const std::vector<double>& lost_s, double widest_s) {
  if (lost_s.size() != io::kLossCauses) return "";
  double total_s = 0;
  for (const double c : lost_s) total_s += c;
  std::string bar;
  for (std::size_t i = 0; i < lost_s.size(); ++i) {
    if (lost_s[i] <= 0 || widest_s <= 0) continue;
    bar += fmt::format(
        R"(<span class="c" style="width:{:.2f}%;background:{}" title="{}: {:.3f} s"></span>)",
        100 * lost_s[i] / widest_s, kCauseColour[i],
        io::loss_cause_name(static_cast<io::LossCause>(i)), lost_s[i]);
  }
  std::array<std::size_t, io::kLossCauses> order{};
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return lost_s[a] > lost_s[b]; });
  std::string words;
  for (std::size_t k = 0; k < 2; ++k) {
    const std::size_t i = order[k];
    if (total_s <= 0 || lost_s[i] < 0.005 * total_s) break;  // shown as 0 %
    words +=
        fmt::format("{}{} {:.0f} %", words.empty() ? "" : ", ",
                    io::loss_cause_name(static_cast<io::LossCause>(i)), 100 * lost_s[i] / total_s);
  }
  return fmt::format("<div class=\"causes\">{}</div>{}", bar, words);
}

// The batch's time lost by cause: a table of seconds and shares with the bar colours.
std::string causes_table(const std::vector<ProgramResult>& results) {
  std::array<double, io::kLossCauses> sum{};
  double total_s = 0;
  for (const ProgramResult& r : results) {
    if (!r.ok || r.lost_by_cause_s.size() != io::kLossCauses) continue;
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += r.lost_by_cause_s[i];
  }
  for (const double c : sum) total_s += c;
  std::string o =
      "<h2>Time lost by cause, all programs</h2>\n<table id=\"causes\">\n"
      "<tr><th class=\"p\">cause</th><th>time lost s</th><th>share</th></tr>\n";
  for (std::size_t i = 0; i < sum.size(); ++i) {
    o += fmt::format(
        "<tr><td class=\"p\"><span class=\"c\" style=\"width:1em;background:{}\"></span> {}</td>"
        "<td>{:.3f}</td><td>{:.1f} %</td></tr>\n",
        kCauseColour[i], io::loss_cause_name(static_cast<io::LossCause>(i)), sum[i],
        total_s > 0 ? 100 * sum[i] / total_s : 0.0);
  }
  o += fmt::format("<tr><td class=\"p\">total</td><td>{:.3f}</td><td></td></tr>\n</table>\n",
                   total_s);
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
  r.lost_by_cause_s.clear();
  if (j.contains("time_lost_by_cause_s") && j["time_lost_by_cause_s"].is_object()) {
    const auto& c = j["time_lost_by_cause_s"];
    for (std::size_t i = 0; i < io::kLossCauses; ++i) {
      r.lost_by_cause_s.push_back(c.value(cause_key(i), 0.0));
    }
  }
  return true;
}

std::string results_csv(const std::vector<ProgramResult>& results) {
  std::string o = "program,status,cycle_time_s,path_length_mm,blocks,cycles,time_lost_s";
  for (std::size_t i = 0; i < io::kLossCauses; ++i) o += fmt::format(",lost_{}_s", cause_key(i));
  o += ",slowest_lines,error\n";
  for (const ProgramResult& r : results) {
    if (!r.ok) {
      o += fmt::format("{},error,,,,,{},,{}\n", csv_field(r.program),
                       std::string(io::kLossCauses, ','), csv_field(r.error));
      continue;
    }
    o += fmt::format("{},ok,{:.6f},{:.6f},{},{},{:.6f}", csv_field(r.program), r.cycle_time_s,
                     r.path_length_mm, r.blocks, r.cycles, r.time_lost_s);
    for (std::size_t i = 0; i < io::kLossCauses; ++i) {
      if (r.lost_by_cause_s.size() == io::kLossCauses) {
        o += fmt::format(",{:.6f}", r.lost_by_cause_s[i]);
      } else {
        o += ',';
      }
    }
    o += fmt::format(",{},\n", csv_field(slow_lines_text(r.slowest)));
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
      ".bar{background:#4a7ebb;height:10px}\n"
      ".causes{display:flex;height:10px;min-width:12em}.c{display:inline-block;height:10px}\n"
      "td.n{white-space:nowrap;font-size:90%}\n"
      "</style></head><body>\n"
      "<h1>Cycle-time estimate</h1>\n";
  o += fmt::format(
      "<p>{} programs on {}: {} ok, {} failed. Total cycle time {:.3f} s ({:.2f} h). "
      "Estimated in {:.1f} s of wall time with {} worker processes.</p>\n",
      results.size(), escape_html(machine), results.size() - failed, failed, total_s,
      total_s / 3600, wall_s, jobs);
  o += "<table id=\"ranking\">\n<tr><th>rank</th><th class=\"p\">program</th><th>cycle time "
       "s</th><th class=\"p\"></th><th>path mm</th><th>blocks</th><th>time lost s</th>"
       "<th class=\"p\">by cause</th><th class=\"p\">slowest lines (line: s lost)</th></tr>\n";
  double widest_lost_s = 0;
  for (const ProgramResult& r : results) {
    double t = 0;
    for (const double c : r.lost_by_cause_s) t += c;
    widest_lost_s = std::max(widest_lost_s, t);
  }
  std::size_t rank = 0;
  for (const ProgramResult* r : ranked) {
    ++rank;
    if (!r->ok) {
      o += fmt::format(
          "<tr class=\"failed\"><td>{}</td><td class=\"p\">{}</td><td class=\"e\" "
          "colspan=\"7\">{}</td></tr>\n",
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
        "<td class=\"p\" style=\"min-width:12em\"><div class=\"bar\" style=\"width:{:.1f}%\"></div>"
        "</td><td>{:.1f}</td><td>{}</td><td>{:.3f}</td><td class=\"p n\">{}</td>"
        "<td class=\"p n\">{}</td></tr>\n",
        rank, escape_html(r->program), r->cycle_time_s, width_pct, r->path_length_mm, r->blocks,
        r->time_lost_s, causes_cell(r->lost_by_cause_s, widest_lost_s), slow);
  }
  o += "</table>\n";
  o += causes_table(results);
  o += "<p>Cycle times are those of <code>cncore run</code> on each program. Time lost is the "
       "program's whole loss against the programmed feed × override; by cause, it is against F "
       "as written and split as <code>cncore run --report</code> splits it (docs/reports.md).</p>\n"
       "</body></html>\n";
  return o;
}

}  // namespace cncore::app::estimate
