// The reader (the seed's reading section 10): table text → header + rows. It only checks the
// syntax; reference values, shifts and the machine are checked by the analysis (plan_tables).
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "tables/table.hpp"

namespace cncore::tables {
namespace {

int axis_slot(char c) {
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (kAxisLetters[i] == c) return static_cast<int>(i);
  }
  return -1;
}

std::string axes_text(std::uint32_t mask) {
  std::string s;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if ((mask >> i) & 1U) {
      if (!s.empty()) s += ' ';
      s += kAxisLetters[i];
    }
  }
  return s;
}

// One line with comments blanked out (columns preserved) and letters upper-cased.
class LineScanner {
 public:
  LineScanner(const std::string& file, std::uint32_t line_no, std::string text)
      : file_(file), line_(line_no), s_(std::move(text)) {
    bool in_paren = false;
    std::uint32_t paren_col = 0;
    for (std::size_t i = 0; i < s_.size(); ++i) {
      char& c = s_[i];
      if (in_paren) {
        if (c == ')') in_paren = false;
        c = ' ';
      } else if (c == '(') {
        in_paren = true;
        paren_col = static_cast<std::uint32_t>(i + 1);
        c = ' ';
      } else if (c == ';') {
        s_.resize(i);
        break;
      } else if (c == '\t' || c == '\r') {
        c = ' ';
      } else {
        c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      }
    }
    if (in_paren) fail(paren_col, "comment '(' is not closed on this line");
  }

  [[noreturn]] void fail(std::uint32_t col, const std::string& msg) const {
    throw InputError(file_, line_, col, msg);
  }
  std::uint32_t col() const { return static_cast<std::uint32_t>(i_ + 1); }
  void skip_space() {
    while (i_ < s_.size() && s_[i_] == ' ') ++i_;
  }
  bool at_end() {
    skip_space();
    return i_ >= s_.size();
  }
  char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  void advance(std::size_t n = 1) { i_ += n; }
  bool starts_with(std::string_view w) const { return s_.compare(i_, w.size(), w) == 0; }
  // A run of letters (a keyword).
  std::string word() {
    std::size_t b = i_;
    while (i_ < s_.size() && std::isalpha(static_cast<unsigned char>(s_[i_]))) ++i_;
    return s_.substr(b, i_ - b);
  }
  // A decimal number (optional sign, digits, optional fraction); false when there is none.
  bool number(double& out) {
    skip_space();
    std::size_t b = i_;
    bool neg = false;
    if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) {
      neg = s_[i_] == '-';
      ++i_;
    }
    std::size_t digits_begin = i_;
    bool any_digit = false;
    while (i_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[i_])) || s_[i_] == '.')) {
      any_digit = any_digit || s_[i_] != '.';
      ++i_;
    }
    if (!any_digit) {
      i_ = b;
      return false;
    }
    double v = 0;
    auto [ptr, ec] = std::from_chars(s_.data() + digits_begin, s_.data() + i_, v);
    if (ec != std::errc() || ptr != s_.data() + i_) {
      fail(static_cast<std::uint32_t>(b + 1), "malformed number '" + s_.substr(b, i_ - b) + "'");
    }
    out = neg ? -v : v;
    return true;
  }
  int integer(std::uint32_t word_col, const std::string& what) {
    double v = 0;
    std::uint32_t c = col();
    if (!number(v)) fail(word_col, "missing number after " + what);
    if (v < 0 || v != std::floor(v) || v > 1e9) {
      fail(c, what + " needs a non-negative whole number");
    }
    return static_cast<int>(v);
  }

 private:
  const std::string& file_;
  std::uint32_t line_;
  std::string s_;
  std::size_t i_ = 0;
};

void parse_header(LineScanner& sc, const std::string& kw, std::uint32_t kw_col,
                  std::uint32_t line_no, Table& t, bool& have_ref) {
  if (kw == "REF") {
    if (have_ref) sc.fail(kw_col, "a second REF header");
    have_ref = true;
    t.ref_line = line_no;
    t.ref_col = kw_col;
    sc.skip_space();
    std::uint32_t c = sc.col();
    std::string kind = sc.word();
    if (kind == "TIME") {
      t.ref_kind = RefKind::kTime;
    } else if (kind == "SPINDLE") {
      t.ref_kind = RefKind::kSpindle;
    } else if (kind == "AXIS") {
      t.ref_kind = RefKind::kAxis;
      sc.skip_space();
      std::uint32_t ac = sc.col();
      std::string a = sc.word();
      if (a.size() != 1 || axis_slot(a[0]) < 0) {
        sc.fail(ac, "REF AXIS needs an axis letter (X Y Z A B C)");
      }
      t.ref_axis = static_cast<std::size_t>(axis_slot(a[0]));
    } else {
      sc.fail(c, "unknown reference kind '" + kind + "' (TIME, AXIS <axis>, SPINDLE)");
    }
  } else if (kw == "AXES") {
    if (t.axes_line != 0) sc.fail(kw_col, "a second AXES header");
    t.axes_line = line_no;
    while (!sc.at_end()) {
      if (sc.peek() == ',') {
        sc.advance();
        continue;
      }
      std::uint32_t c = sc.col();
      int slot = axis_slot(sc.peek());
      if (slot < 0) sc.fail(c, std::string("'") + sc.peek() + "' is not an axis (X Y Z A B C)");
      if ((t.axis_mask >> slot) & 1U) sc.fail(c, std::string("axis ") + sc.peek() + " twice");
      t.axis_mask |= 1U << slot;
      t.axis_cols[static_cast<std::size_t>(slot)] = c;
      sc.advance();
    }
    if (t.axis_mask == 0) sc.fail(kw_col, "AXES names no axis");
    return;
  } else if (kw == "LINEAR") {
    t.interp = Interp::kLinear;
  } else if (kw == "CUBIC") {
    t.interp = Interp::kCubic;
  } else if (kw == "CYCLIC") {
    t.cyclic = true;
    if (!sc.at_end()) {
      std::uint32_t c = sc.col();
      t.cyclic_repeats = static_cast<std::uint32_t>(sc.integer(kw_col, "CYCLIC"));
      if (t.cyclic_repeats == 0) sc.fail(c, "CYCLIC needs at least 1 repetition");
    }
  } else {
    sc.fail(kw_col, "unknown word '" + kw + "'");
  }
  if (!sc.at_end()) sc.fail(sc.col(), "unexpected text after " + kw);
}

void parse_shift(LineScanner& sc, std::uint32_t sft_col, Row& row) {
  row.shift.col = sft_col;
  sc.skip_space();
  if (sc.peek() == '=') {
    sc.advance();
    sc.skip_space();
    char k = sc.peek();
    std::uint32_t kc = sc.col();
    if (k == 'P') {
      row.shift.kind = Shift::Kind::kParam;
    } else if (k == '#') {
      row.shift.kind = Shift::Kind::kMacro;
    } else if (k == 'R') {
      row.shift.kind = Shift::Kind::kSignal;
    } else {
      sc.fail(kc, "SFT= needs P<n>, #<n> or R<n>");
    }
    sc.advance();
    row.shift.number = sc.integer(kc, std::string("SFT=") + k);
    return;
  }
  double v = 0;
  if (!sc.number(v)) sc.fail(sft_col, "missing amount after SFT");
  row.shift.kind = Shift::Kind::kDirect;
  row.shift.amount = v;
}

Row parse_row(LineScanner& sc, std::uint32_t line_no, const Table& t) {
  Row row;
  row.line = line_no;
  bool have_l = false;
  std::uint32_t first_col = 0;
  while (!sc.at_end()) {
    std::uint32_t c = sc.col();
    if (first_col == 0) first_col = c;
    if (sc.starts_with("SFTCAN")) {
      if (row.cancel) sc.fail(c, "SFTCAN twice in one row");
      row.cancel = true;
      row.cancel_col = c;
      sc.advance(6);
      continue;
    }
    if (sc.starts_with("SFT")) {
      if (row.shift.kind != Shift::Kind::kNone) sc.fail(c, "two SFT in one row");
      sc.advance(3);
      parse_shift(sc, c, row);
      continue;
    }
    char letter = sc.peek();
    if (!std::isalpha(static_cast<unsigned char>(letter))) {
      sc.fail(c, std::string("unexpected character '") + letter + "'");
    }
    sc.advance();
    char next = sc.peek();
    if (std::isalpha(static_cast<unsigned char>(next))) {
      sc.fail(c, std::string("unknown address '") + letter + next + "...'");
    }
    double v = 0;
    int slot = axis_slot(letter);
    if (letter == 'L') {
      if (have_l) sc.fail(c, "two L words in one row");
      if (!sc.number(v)) sc.fail(c, "missing reference value after L");
      have_l = true;
      row.col = c;
      row.ref_written = v;
    } else if (letter == 'M') {
      row.m_codes.push_back(sc.integer(c, "M"));
    } else if (letter == 'N') {
      sc.integer(c, "N");
    } else if (slot >= 0) {
      if (!((t.axis_mask >> slot) & 1U)) {
        sc.fail(c, std::string("axis ") + letter + " is not driven by this table (AXES " +
                       axes_text(t.axis_mask) + ")");
      }
      if ((row.axis_mask >> slot) & 1U) sc.fail(c, std::string("axis ") + letter + " twice");
      if (!sc.number(v)) sc.fail(c, std::string("missing value after ") + letter);
      row.axis_mask |= 1U << slot;
      row.target[static_cast<std::size_t>(slot)] = v;
    } else {
      sc.fail(c, std::string("unknown address '") + letter + "'");
    }
  }
  if (!have_l) sc.fail(first_col, "row without reference value L");
  if (row.cancel && row.shift.kind != Shift::Kind::kNone) {
    sc.fail(row.cancel_col, "SFT and SFTCAN in one row");
  }
  return row;
}

}  // namespace

Table parse_table(std::string_view text, const std::string& file) {
  Table t;
  t.file = file;
  bool have_ref = false;
  std::uint32_t line_no = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    ++line_no;
    LineScanner sc(file, line_no, std::string(text.substr(pos, eol - pos)));
    pos = eol + 1;
    if (sc.at_end()) continue;
    if (sc.peek() == '%') {
      sc.advance();
      if (!sc.at_end()) sc.fail(sc.col(), "unexpected text after %");
      continue;
    }
    std::uint32_t c = sc.col();
    // A header line starts with a keyword of two letters or more; a row with an address
    // (L1000, N10, X..., SFT...).
    LineScanner probe = sc;
    std::string kw = probe.word();
    if (kw.size() >= 2 && kw.rfind("SFT", 0) != 0) {
      if (!t.rows.empty()) sc.fail(c, kw + " must come before the first row");
      parse_header(probe, kw, c, line_no, t, have_ref);
      continue;
    }
    if (!have_ref) sc.fail(c, "missing REF header (REF TIME, REF AXIS <axis> or REF SPINDLE)");
    if (t.axes_line == 0) sc.fail(c, "missing AXES header (for example AXES X Z)");
    t.rows.push_back(parse_row(sc, line_no, t));
  }
  if (!have_ref) throw InputError(file, 1, 1, "missing REF header");
  if (t.axes_line == 0) throw InputError(file, t.ref_line, 1, "missing AXES header");
  if (t.rows.empty()) throw InputError(file, t.axes_line, 1, "table has no rows");
  if (t.ref_kind == RefKind::kAxis && ((t.axis_mask >> t.ref_axis) & 1U)) {
    throw InputError(file, t.axes_line, t.axis_cols[t.ref_axis],
                     std::string("axis ") + kAxisLetters[t.ref_axis] +
                         " is the reference (REF AXIS) and cannot be driven by the table");
  }
  if (t.cyclic && t.rows.size() < 2) {
    throw InputError(file, t.rows.front().line, t.rows.front().col,
                     "a CYCLIC table needs at least two rows");
  }
  return t;
}

Table load_table(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, 0, 0,
                     std::string("cannot open the table file: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_table(ss.str(), path);
}

std::pair<int, double> parse_signal(std::string_view text, const std::string& option) {
  std::string s(text);
  LineScanner sc(option, 0, s);
  sc.skip_space();
  if (sc.peek() != 'R') sc.fail(sc.col(), "expected R<n>=VALUE, got '" + s + "'");
  sc.advance();
  int n = sc.integer(sc.col(), "R");
  sc.skip_space();
  if (sc.peek() != '=') sc.fail(sc.col(), "expected '=' in R<n>=VALUE");
  sc.advance();
  double v = 0;
  if (!sc.number(v)) sc.fail(sc.col(), "missing value after '='");
  if (!sc.at_end()) sc.fail(sc.col(), "unexpected text in '" + s + "'");
  return {n, v};
}

SignalChange parse_signal_at(std::string_view text, const std::string& option) {
  std::size_t colon = text.find(':');
  if (colon == std::string_view::npos) {
    throw InputError(option, 0, 1, "expected T:R<n>=VALUE, got '" + std::string(text) + "'");
  }
  LineScanner sc(option, 0, std::string(text.substr(0, colon)));
  double t = 0;
  if (!sc.number(t) || !sc.at_end() || t < 0) {
    throw InputError(option, 0, 1, "time before ':' must be a number of seconds >= 0");
  }
  auto [n, v] = parse_signal(text.substr(colon + 1), option);
  return {t, n, v};
}

}  // namespace cncore::tables
