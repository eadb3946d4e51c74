// An output file that appears complete or not at all: data goes to FILE.tmp-XXXXXX in the same
// directory (so the final rename stays on one file system and is atomic), commit() renames it
// over FILE, and destruction without commit removes the temporary. A failed run therefore
// leaves neither a half-written file nor a temporary behind, even when it is interrupted by
// SIGINT, SIGTERM or SIGHUP (a handler removes the open temporaries, then the process dies of
// the signal as usual). An existing device or pipe (/dev/null, a FIFO) is written directly
// instead: there is no file to leave half-written, and a rename would replace the node.
#pragma once

#include <string>
#include <string_view>

namespace cncore::io {

class AtomicOutputFile {
 public:
  // Creates the temporary file. Throws InputError(path, 0, 0, ...) when it cannot be created.
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  // Appends bytes (unbuffered: callers write large chunks). Throws InputError on a write error.
  void write(std::string_view data);
  // Closes the temporary and renames it to the final path. Throws InputError on failure (the
  // temporary is then removed).
  void commit();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_; }
  bool committed() const { return committed_; }

 private:
  void discard() noexcept;

  std::string path_;
  std::string temp_;
  int fd_ = -1;
  int signal_slot_ = -1;  // entry in the list the SIGINT/SIGTERM handler cleans up
  bool committed_ = false;
};

}  // namespace cncore::io
