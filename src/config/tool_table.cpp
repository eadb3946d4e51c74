#include "config/tool_table.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace cncore {

namespace {

struct LineParser {
  const std::string& file;
  std::uint32_t line;
  std::string_view text;

  [[noreturn]] void fail(std::size_t at, const std::string& message) const {
    throw InputError(file, line, static_cast<std::uint32_t>(at + 1), message);
  }
};

bool blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

// One line "T1 P1 Z12.5 D6 ;comment" into `t`; false for a blank or comment-only line.
bool parse_line(const LineParser& p, ToolEntry& t) {
  bool have_tool = false, any = false;
  const std::string_view s = p.text;
  std::size_t i = 0;
  while (i < s.size()) {
    if (blank(s[i])) {
      ++i;
      continue;
    }
    if (s[i] == ';') break;
    const std::size_t at = i;
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(s[i++])));
    std::size_t end = i;
    while (end < s.size() && !blank(s[end]) && s[end] != ';') ++end;
    double v = 0;
    const char* b = s.data() + i;
    const char* e = s.data() + end;
    if (*b == '+') ++b;  // fast_float takes no leading '+'
    const auto r = fast_float::from_chars(b, e, v);
    if (i == end || r.ec != std::errc() || r.ptr != e || !std::isfinite(v)) {
      p.fail(at, fmt::format("tool table: '{}' is not a letter followed by a number",
                             std::string(s.substr(at, end - at))));
    }
    any = true;
    auto count = [&](const char* what) {
      if (v < 0 || v != std::floor(v) || v > 1e9) {
        p.fail(at, fmt::format("tool table: {} must be a non-negative integer", what));
      }
      return static_cast<std::uint32_t>(v);
    };
    switch (letter) {
      case 'T':
        t.number = count("the tool number T");
        have_tool = true;
        break;
      case 'P':
        t.pocket = count("the pocket P");
        break;
      case 'X':
      case 'Y':
      case 'Z':
        t.offset_mm[static_cast<std::size_t>(letter - 'X')] = v;
        break;
      case 'A':
      case 'B':
      case 'C':
        t.offset_mm[static_cast<std::size_t>(3 + letter - 'A')] = v;
        break;
      case 'U':
      case 'V':
      case 'W':
        if (v != 0) {
          p.fail(at, fmt::format("tool table: {} offset: cncore has no {} axis", letter, letter));
        }
        break;
      case 'D':
        if (v < 0) p.fail(at, "tool table: negative diameter D");
        t.diameter_mm = v;
        break;
      case 'I':
      case 'J':
      case 'Q':
        break;  // lathe tool angles and orientation: nothing to apply on a mill
      default:
        p.fail(at, fmt::format("tool table: unknown word '{}'", letter));
    }
    i = end;
  }
  if (any && !have_tool) p.fail(0, "tool table: a line without T (tool number)");
  return any;
}

// The words of a line split at blanks, with the column where each starts.
std::vector<std::pair<std::size_t, std::string_view>> words_of(std::string_view s) {
  std::vector<std::pair<std::size_t, std::string_view>> out;
  for (std::size_t i = 0; i < s.size();) {
    if (blank(s[i])) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < s.size() && !blank(s[end])) ++end;
    out.emplace_back(i, s.substr(i, end - i));
    i = end;
  }
  return out;
}

// LinuxCNC's older column format: a header "POC FMS LEN DIAM COMMENT" (mill) or "POC FMS
// ZOFFSET XOFFSET DIA FRONTANGLE BACKANGLE ORIENT COMMENT" (lathe), then one row per tool; FMS
// is the tool number. The columns are read by the header's names.
bool parse_legacy_line(const LineParser& p, const std::vector<std::string>& columns, ToolEntry& t) {
  const auto words = words_of(p.text);
  if (words.empty() || words.front().second.front() == ';') return false;
  bool have_tool = false;
  for (std::size_t k = 0; k < words.size() && k < columns.size(); ++k) {
    const std::string& name = columns[k];
    if (name == "COMMENT") break;
    const std::size_t at = words[k].first;
    const std::string_view text = words[k].second;
    double v = 0;
    const auto r = fast_float::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v)) {
      p.fail(at, fmt::format("tool table: '{}' is not a number (column {})", text, name));
    }
    auto count = [&] {
      if (v < 0 || v != std::floor(v) || v > 1e9) {
        p.fail(at, fmt::format("tool table: {} must be a non-negative integer", name));
      }
      return static_cast<std::uint32_t>(v);
    };
    if (name == "POC") t.pocket = count();
    if (name == "FMS") {
      t.number = count();
      have_tool = true;
    }
    if (name == "LEN" || name == "ZOFFSET") t.offset_mm[2] = v;
    if (name == "XOFFSET") t.offset_mm[0] = v;
    if (name == "DIAM" || name == "DIA") t.diameter_mm = std::fabs(v);
  }
  if (!have_tool) p.fail(0, "tool table: a row without its FMS (tool number) column");
  return true;
}

}  // namespace

ToolTable parse_tool_table(const std::string& text, const std::string& source_name) {
  ToolTable table;
  std::uint32_t line = 0;
  std::size_t pos = 0;
  std::vector<std::string> legacy_columns;  // set by a "POC FMS …" header
  while (pos <= text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    ++line;
    const LineParser p{source_name, line, std::string_view(text).substr(pos, end - pos)};
    ToolEntry t;
    const auto words = words_of(p.text);
    if (table.empty() && legacy_columns.empty() && !words.empty() && words[0].second == "POC") {
      for (const auto& w : words) legacy_columns.emplace_back(w.second);
    } else if (legacy_columns.empty() ? parse_line(p, t)
                                      : parse_legacy_line(p, legacy_columns, t)) {
      if (!table.try_emplace(t.number, t).second) {
        p.fail(0, fmt::format("tool table: tool {} is listed twice", t.number));
      }
    }
    if (nl == std::string::npos) break;
    pos = nl + 1;
  }
  return table;
}

ToolTable read_tool_table(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, 0, "cannot open the tool table: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open the tool table");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_tool_table(text.str(), path);
}

}  // namespace cncore
