#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/error.hpp"

namespace cncore::io {

namespace {

std::string errno_text() {
  return std::strerror(errno);
}

// Temporaries still open, so that an interrupted run (Ctrl-C, SIGTERM from a timeout) removes
// them too: the signal handler unlinks them (unlink is async-signal-safe) and then dies of the
// signal as it would have. Fixed storage: nothing to allocate in the handler.
constexpr int kMaxTemps = 16;
constexpr std::size_t kMaxPath = 4096;
char g_temp_paths[kMaxTemps][kMaxPath];
volatile std::sig_atomic_t g_temp_used[kMaxTemps];

extern "C" void remove_temps_and_die(int sig) {
  for (int i = 0; i < kMaxTemps; ++i) {
    if (g_temp_used[i]) ::unlink(g_temp_paths[i]);
  }
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

void install_handlers_once() {
  static bool installed = false;
  if (installed) return;
  installed = true;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    ::sigaction(sig, nullptr, &old);
    if (old.sa_handler != SIG_DFL) continue;  // ignored or handled elsewhere: leave it
    struct sigaction sa {};
    sa.sa_handler = remove_temps_and_die;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

int register_temp(const std::string& path) {
  if (path.size() >= kMaxPath) return -1;
  install_handlers_once();
  for (int i = 0; i < kMaxTemps; ++i) {
    if (!g_temp_used[i]) {
      std::memcpy(g_temp_paths[i], path.c_str(), path.size() + 1);
      g_temp_used[i] = 1;
      return i;
    }
  }
  return -1;
}

void unregister_temp(int slot) {
  if (slot >= 0) g_temp_used[slot] = 0;
}

}  // namespace

AtomicOutputFile::AtomicOutputFile(std::string path) : path_(std::move(path)) {
  // A device or a pipe (/dev/null, /dev/stdout, a FIFO) is written directly: renaming a
  // temporary over it would replace the device node with a regular file (as root, /dev/null).
  struct stat st {};
  if (::stat(path_.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) throw InputError(path_, 0, 0, "cannot open output file: " + errno_text());
    return;
  }
  std::vector<char> name(path_.begin(), path_.end());
  const char suffix[] = ".tmp-XXXXXX";
  name.insert(name.end(), suffix, suffix + sizeof(suffix));  // includes the terminating NUL
  fd_ = ::mkstemp(name.data());
  if (fd_ < 0) throw InputError(path_, 0, 0, "cannot create output file: " + errno_text());
  temp_ = name.data();
  signal_slot_ = register_temp(temp_);
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
  unregister_temp(signal_slot_);
  signal_slot_ = -1;
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
  if (temp_.empty()) {  // written directly (a device or a pipe)
    committed_ = true;
    return;
  }
  if (::rename(temp_.c_str(), path_.c_str()) != 0) {
    const std::string why = errno_text();
    discard();
    throw InputError(path_, 0, 0, "cannot rename output file into place: " + why);
  }
  temp_.clear();
  unregister_temp(signal_slot_);
  signal_slot_ = -1;
  committed_ = true;
}

}  // namespace cncore::io
