// Lexical layer: turns one raw program line into the normalised form that RS274/NGC parses
// (LinuxCNC rules): comments "( )" and ";" removed, spaces and tabs removed anywhere outside
// comments (so "X 1 0.5" is X10.5), everything lower case. A column map keeps the original
// 1-based column of every remaining character for error messages.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace cncore::interp {

// Where an error is reported: the file and the line being interpreted.
struct ErrorContext {
  const std::string* file = nullptr;
  std::uint32_t line = 0;
  [[noreturn]] void fail(std::uint32_t col, const std::string& message) const;
};

struct NormLine {
  std::string text;                 // normalised text
  std::vector<std::uint32_t> cols;  // cols[i]: original column of text[i]; one extra = end
  bool block_delete = false;        // the line starts with "/"
  bool percent = false;             // the line is a "%" program delimiter
  // A "(msg,TEXT)" or "(debug,TEXT)" comment (LinuxCNC's operator messages): its TEXT, as
  // written; the last one of the line.
  enum class Message : std::uint8_t { kNone, kMsg, kDebug };
  Message message = Message::kNone;
  std::string message_text;

  std::uint32_t col(std::size_t i) const {
    return i < cols.size() ? cols[i] : (cols.empty() ? 1 : cols.back());
  }
};

// Normalises `raw` into `out` (buffers are reused between lines). Throws InputError for an
// unclosed or nested comment.
void normalize_line(std::string_view raw, NormLine& out, const ErrorContext& ctx);

// Scans an unsigned decimal number (digits with at most one '.') at text[pos]; no sign, no
// exponent (RS274/NGC has none). On success stores the value, advances pos and returns true.
// A second '.' right after the number is reported as a bad number.
bool scan_number(const NormLine& line, std::size_t& pos, double& value, const ErrorContext& ctx);

// `text` for an error message: bytes outside printable ASCII (NUL, control characters, UTF-8)
// are written as \xHH, so the message is one clean line whatever the program holds.
std::string printable(std::string_view text);
inline std::string printable(char c) {
  return printable(std::string_view(&c, 1));
}

inline bool is_digit(char c) {
  return c >= '0' && c <= '9';
}
inline bool is_lower(char c) {
  return c >= 'a' && c <= 'z';
}

}  // namespace cncore::interp
