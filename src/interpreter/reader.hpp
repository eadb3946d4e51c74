// Streaming line reader for part programs: reads the file in fixed-size chunks and hands out
// one line at a time, remembering the byte offset of every line so that loops and subroutine
// calls can seek back. Memory is one chunk plus the longest line, whatever the file size.
// A pulled reader takes its lines from a function (a controller's queue of streamed lines): it
// cannot seek back, so loops and subroutine calls are refused there.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>

namespace cncore::interp {

// Where a line starts: enough to seek back to it.
struct LinePos {
  std::uint64_t offset = 0;  // byte offset of the first character of the line
  std::uint32_t line = 1;    // 1-based line number
};

class LineReader {
 public:
  // Reads a file (throws InputError naming the file when it cannot be opened).
  static LineReader open_file(const std::string& path);
  // Reads text held in memory.
  static LineReader from_text(std::string text);
  // Takes each line from `pull` (false: the input has ended); `pull` may block.
  using Pull = std::function<bool(std::string& line)>;
  static LineReader pulled(Pull pull);

  LineReader(LineReader&& other) noexcept;
  LineReader& operator=(LineReader&&) = delete;
  LineReader(const LineReader&) = delete;
  ~LineReader();

  // The next line without its end-of-line characters ("\n", "\r\n", "\r"). The view stays valid
  // until the next call. Returns false at the end of the input.
  bool next(std::string_view& line);
  // Position of the line last returned by next().
  LinePos current() const { return current_; }
  // Position of the line that next() will return.
  LinePos following() const { return following_; }
  // Makes next() return the line at `pos` (a position previously obtained from this reader).
  // A pulled reader can only stay where it is: it throws InputError(name, line, 0, …) otherwise.
  void seek(LinePos pos);
  // Lines come from a pull function (no seeking back).
  bool is_pulled() const { return static_cast<bool>(pull_); }
  // The program name a pulled reader's seek error names.
  void set_name(std::string name) { name_ = std::move(name); }

 private:
  LineReader() = default;
  bool fill();  // reads the next chunk into buf_; false at end of file
  bool next_line(std::string_view& line);

  std::FILE* file_ = nullptr;
  std::string text_;  // the whole program when reading from memory
  bool in_memory_ = false;
  Pull pull_;  // pulled reader
  std::string pulled_line_;
  std::string name_;

  std::string buf_;  // current chunk (file mode)
  std::size_t buf_pos_ = 0;
  std::uint64_t buf_offset_ = 0;  // file offset of buf_[0]
  bool eof_ = false;
  std::string carry_;  // a line that straddles two chunks

  LinePos current_;
  LinePos following_;
};

}  // namespace cncore::interp
