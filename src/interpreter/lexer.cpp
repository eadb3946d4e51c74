#include "interpreter/lexer.hpp"

#include <fast_float/fast_float.h>

#include "core/error.hpp"

namespace cncore::interp {

void ErrorContext::fail(std::uint32_t col, const std::string& message) const {
  throw InputError(file != nullptr ? *file : std::string("<program>"), line, col, message);
}

std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto u = static_cast<unsigned char>(ch);
    if (u >= 0x20 && u < 0x7f) {
      out.push_back(ch);
    } else {
      out += "\\x";
      out.push_back(kHex[u >> 4]);
      out.push_back(kHex[u & 0xf]);
    }
  }
  return out;
}

namespace {

// "msg," / "debug," (any case, blanks before them) opening a comment: keep its text.
void message_comment(std::string_view c, NormLine& out) {
  std::size_t k = 0;
  while (k < c.size() && (c[k] == ' ' || c[k] == '\t')) ++k;
  auto opens = [&](std::string_view key) {
    if (c.size() - k < key.size()) return false;
    for (std::size_t j = 0; j < key.size(); ++j) {
      const char ch = c[k + j];
      if ((ch >= 'A' && ch <= 'Z' ? static_cast<char>(ch - 'A' + 'a') : ch) != key[j]) {
        return false;
      }
    }
    return true;
  };
  if (opens("msg,")) {
    out.message = NormLine::Message::kMsg;
    out.message_text = c.substr(k + 4);
  } else if (opens("debug,")) {
    out.message = NormLine::Message::kDebug;
    out.message_text = c.substr(k + 6);
  }
}

}  // namespace

void normalize_line(std::string_view raw, NormLine& out, const ErrorContext& ctx) {
  out.block_delete = false;
  out.percent = false;
  out.message = NormLine::Message::kNone;
  // Hot path: write through raw pointers into buffers sized for the whole line, then trim.
  const std::size_t n = raw.size();
  out.text.resize(n);
  out.cols.resize(n + 1);
  char* text = out.text.data();
  std::uint32_t* cols = out.cols.data();
  std::size_t len = 0;

  std::size_t i = 0;
  // Leading blanks, then an optional block-delete slash (only as the first character).
  while (i < n && (raw[i] == ' ' || raw[i] == '\t')) ++i;
  if (i < n && raw[i] == '/') {
    out.block_delete = true;
    ++i;
  }
  for (; i < n; ++i) {
    const char c = raw[i];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') continue;
    if (c == ';') break;  // the rest of the line is a comment
    if (c == '(') {
      const std::size_t open = i;
      for (++i; i < n && raw[i] != ')'; ++i) {
        if (raw[i] == '(') {
          ctx.fail(static_cast<std::uint32_t>(i + 1), "nested comment: '(' inside a comment");
        }
      }
      if (i >= n) {
        ctx.fail(static_cast<std::uint32_t>(open + 1), "unclosed comment: '(' without ')'");
      }
      message_comment(raw.substr(open + 1, i - open - 1), out);
      continue;
    }
    if (c == ')') ctx.fail(static_cast<std::uint32_t>(i + 1), "')' without '(' (comment)");
    text[len] = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    cols[len] = static_cast<std::uint32_t>(i + 1);
    ++len;
  }
  cols[len] = static_cast<std::uint32_t>(n + 1);
  out.text.resize(len);
  out.cols.resize(len + 1);
  if (!out.block_delete && len == 1 && text[0] == '%') out.percent = true;
}

bool scan_number(const NormLine& line, std::size_t& pos, double& value, const ErrorContext& ctx) {
  const std::string& t = line.text;
  const std::size_t start = pos;
  std::size_t i = pos;
  bool digits = false;
  // Fast path: a plain integer part accumulated directly.
  while (i < t.size() && is_digit(t[i])) {
    ++i;
    digits = true;
  }
  bool dot = false;
  if (i < t.size() && t[i] == '.') {
    dot = true;
    ++i;
    while (i < t.size() && is_digit(t[i])) {
      ++i;
      digits = true;
    }
  }
  if (!digits) return false;
  if (i < t.size() && t[i] == '.') {
    std::size_t e = i;
    while (e < t.size() && (is_digit(t[e]) || t[e] == '.')) ++e;
    ctx.fail(line.col(start), "bad number '" + printable(t.substr(start, e - start)) + "'");
  }
  if (!dot && i - start <= 15) {
    // Integers are common (N, G, M, small coordinates); skip the float parser for them.
    std::int64_t v = 0;
    for (std::size_t k = start; k < i; ++k) v = v * 10 + (t[k] - '0');
    value = static_cast<double>(v);
  } else {
    const char* b = t.data() + start;
    const char* e = t.data() + i;
    if (*b == '.') {
      // fast_float accepts ".5" in its general format, but be explicit for robustness.
      double frac = 0;
      auto r = fast_float::from_chars(b, e, frac);
      if (r.ec != std::errc()) ctx.fail(line.col(start), "bad number");
      value = frac;
    } else {
      auto r = fast_float::from_chars(b, e, value);
      if (r.ec != std::errc() || r.ptr != e) ctx.fail(line.col(start), "bad number");
    }
  }
  pos = i;
  return true;
}

}  // namespace cncore::interp
