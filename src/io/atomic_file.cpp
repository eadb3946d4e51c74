#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/error.hpp"

namespace cncore::io {

namespace {
std::string errno_text() {
  return std::strerror(errno);
}
}  // namespace

AtomicOutputFile::AtomicOutputFile(std::string path) : path_(std::move(path)) {
  std::vector<char> name(path_.begin(), path_.end());
  const char suffix[] = ".tmp-XXXXXX";
  name.insert(name.end(), suffix, suffix + sizeof(suffix));  // includes the terminating NUL
  fd_ = ::mkstemp(name.data());
  if (fd_ < 0) throw InputError(path_, 0, 0, "cannot create output file: " + errno_text());
  temp_ = name.data();
  // mkstemp creates mode 0600; give the result the usual mode 0666 minus the umask.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd_, static_cast<mode_t>(0666 & ~mask));
}

AtomicOutputFile::~AtomicOutputFile() {
  if (!committed_) discard();
}

void AtomicOutputFile::discard() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!temp_.empty()) {
    ::unlink(temp_.c_str());
    temp_.clear();
  }
}

void AtomicOutputFile::write(std::string_view data) {
  if (fd_ < 0) throw InputError(path_, 0, 0, "write to a closed output file");
  while (!data.empty()) {
    const ssize_t n = ::write(fd_, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path_, 0, 0, "cannot write output file: " + errno_text());
    }
    data.remove_prefix(static_cast<std::size_t>(n));
  }
}

void AtomicOutputFile::commit() {
  if (committed_) return;
  if (fd_ < 0) throw InputError(path_, 0, 0, "output file already discarded");
  const int rc = ::close(fd_);
  fd_ = -1;
  if (rc != 0) {
    const std::string why = errno_text();
    discard();
    throw InputError(path_, 0, 0, "cannot write output file: " + why);
  }
  if (::rename(temp_.c_str(), path_.c_str()) != 0) {
    const std::string why = errno_text();
    discard();
    throw InputError(path_, 0, 0, "cannot rename output file into place: " + why);
  }
  temp_.clear();
  committed_ = true;
}

}  // namespace cncore::io
