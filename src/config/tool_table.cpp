#include "config/tool_table.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

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

}  // namespace

ToolTable parse_tool_table(const std::string& text, const std::string& source_name) {
  ToolTable table;
  std::uint32_t line = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    ++line;
    const LineParser p{source_name, line, std::string_view(text).substr(pos, end - pos)};
    ToolEntry t;
    if (parse_line(p, t)) {
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
