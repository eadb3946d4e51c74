// Errors in user input (programs, tables, configuration, command-line values). They print as
// FILE:LINE:COL: error: MESSAGE and make the command exit with code 1.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace cncore {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::uint32_t line, std::uint32_t col, const std::string& message)
      : std::runtime_error(message), file_(std::move(file)), line_(line), col_(col) {}

  const std::string& file() const { return file_; }
  std::uint32_t line() const { return line_; }
  std::uint32_t col() const { return col_; }
  // "FILE:LINE:COL: error: MESSAGE"
  std::string formatted() const {
    return file_ + ":" + std::to_string(line_) + ":" + std::to_string(col_) + ": error: " + what();
  }

 private:
  std::string file_;
  std::uint32_t line_;
  std::uint32_t col_;
};

}  // namespace cncore
