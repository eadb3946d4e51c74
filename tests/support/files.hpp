// Small file and shell helpers shared by the tests that run the `cncore` binary.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cncore::testing {

// The whole file, bytes as they are ("" when it cannot be opened).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_file(const std::filesystem::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

// s as one single-quoted POSIX shell word.
inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace cncore::testing
