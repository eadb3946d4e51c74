#include "interpreter/reader.hpp"

#include <cerrno>
#include <cstring>

#include "core/error.hpp"

namespace cncore::interp {

namespace {
constexpr std::size_t kChunkBytes = 1 << 16;

constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
}  // namespace

LineReader LineReader::open_file(const std::string& path) {
  LineReader r;
  r.file_ = std::fopen(path.c_str(), "rb");
  if (r.file_ == nullptr) {
    throw InputError(path, 0, 0, std::string("cannot open the program: ") + std::strerror(errno));
  }
  r.buf_.reserve(kChunkBytes);
  return r;
}

LineReader LineReader::from_text(std::string text) {
  LineReader r;
  r.text_ = std::move(text);
  r.in_memory_ = true;
  return r;
}

LineReader LineReader::pulled(Pull pull) {
  LineReader r;
  r.pull_ = std::move(pull);
  return r;
}

LineReader::LineReader(LineReader&& other) noexcept
    : file_(other.file_),
      text_(std::move(other.text_)),
      in_memory_(other.in_memory_),
      pull_(std::move(other.pull_)),
      pulled_line_(std::move(other.pulled_line_)),
      name_(std::move(other.name_)),
      buf_(std::move(other.buf_)),
      buf_pos_(other.buf_pos_),
      buf_offset_(other.buf_offset_),
      eof_(other.eof_),
      carry_(std::move(other.carry_)),
      current_(other.current_),
      following_(other.following_) {
  other.file_ = nullptr;
}

LineReader::~LineReader() {
  if (file_ != nullptr) std::fclose(file_);
}

bool LineReader::fill() {
  if (eof_) return false;
  buf_offset_ += buf_.size();
  buf_.resize(kChunkBytes);
  const std::size_t n = std::fread(buf_.data(), 1, kChunkBytes, file_);
  buf_.resize(n);
  buf_pos_ = 0;
  if (n < kChunkBytes) eof_ = true;
  return n > 0;
}

bool LineReader::next(std::string_view& line) {
  current_ = following_;
  if (!next_line(line)) return false;
  // A UTF-8 byte-order mark (editors on Windows write one) is not part of the program.
  if (current_.offset == 0 && line.substr(0, 3) == kUtf8Bom) line.remove_prefix(3);
  return true;
}

// Lines end at "\n", "\r\n" or a lone "\r" (old Mac editors and some controllers).
bool LineReader::next_line(std::string_view& line) {
  if (pull_) {
    // Offsets count lines here: a pulled line has no place in a file.
    if (!pull_(pulled_line_)) return false;
    line = pulled_line_;
    ++following_.offset;
    ++following_.line;
    return true;
  }
  if (in_memory_) {
    const std::size_t pos = following_.offset;
    if (pos >= text_.size()) return false;
    std::size_t end = text_.find_first_of("\r\n", pos);
    std::size_t after = end;
    if (end == std::string::npos) {
      end = after = text_.size();
    } else {
      after = end + 1;
      if (text_[end] == '\r' && after < text_.size() && text_[after] == '\n') ++after;
    }
    line = std::string_view(text_).substr(pos, end - pos);
    following_.offset = after;
    ++following_.line;
    return true;
  }
  // File mode: the line may start in this chunk and end in a later one.
  carry_.clear();
  bool have_any = false;
  for (;;) {
    if (buf_pos_ >= buf_.size() && !fill()) break;
    const char* begin = buf_.data() + buf_pos_;
    const std::size_t avail = buf_.size() - buf_pos_;
    const std::string_view chunk(begin, avail);
    const std::size_t nl = chunk.find('\n');
    bool found = nl != std::string_view::npos;
    std::size_t len = found ? nl : avail;
    bool cr = false;
    if (const std::size_t at = chunk.substr(0, len).find('\r'); at != std::string_view::npos) {
      len = at;
      found = cr = true;
    }
    have_any = true;
    if (found) {
      // "\r\n" may straddle two chunks: keep the line, then look at the next chunk.
      const bool at_chunk_end = cr && buf_pos_ + len + 1 >= buf_.size();
      if (!carry_.empty() || at_chunk_end) carry_.append(begin, len);
      buf_pos_ += len + 1;
      if (at_chunk_end) fill();
      if (cr && buf_pos_ < buf_.size() && buf_[buf_pos_] == '\n') ++buf_pos_;
      line = carry_.empty() ? (at_chunk_end ? std::string_view() : std::string_view(begin, len))
                            : std::string_view(carry_);
      following_.offset = buf_offset_ + buf_pos_;
      ++following_.line;
      return true;
    }
    carry_.append(begin, avail);
    buf_pos_ += avail;
  }
  if (!have_any || carry_.empty()) return false;
  line = carry_;
  following_.offset = buf_offset_ + buf_.size();
  ++following_.line;
  return true;
}

void LineReader::seek(LinePos pos) {
  if (pull_) {
    if (pos.offset == following_.offset) return;
    throw InputError(name_, current_.line, 0,
                     "loops and subroutine calls cannot run in streamed lines (send a program "
                     "file instead)");
  }
  following_ = pos;
  if (in_memory_) return;
  // Reuse the current chunk when the target lies inside it (tight loops stay in memory).
  if (pos.offset >= buf_offset_ && pos.offset <= buf_offset_ + buf_.size()) {
    buf_pos_ = static_cast<std::size_t>(pos.offset - buf_offset_);
    return;
  }
  std::fseek(file_, static_cast<long>(pos.offset), SEEK_SET);
  eof_ = false;
  buf_.clear();
  buf_offset_ = pos.offset;
  buf_pos_ = 0;
}

}  // namespace cncore::interp
