// Replays fuzz inputs through a fuzz target's LLVMFuzzerTestOneInput without libFuzzer, in the
// normal (gcc, non-fuzz) build: `fuzz_replay_<target> DIR|FILE...` runs every file once. A
// finding aborts (or trips a sanitizer in the asan build), which fails the ctest test that runs
// it; so the crashing inputs kept under fuzz/regressions/<target>/ stay fixed.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

int replay(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::fprintf(stderr, "replay %s (%zu bytes)\n", file.c_str(), bytes.size());
  return LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace

int main(int argc, char** argv) {
  int files = 0;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg(argv[i]);
    if (std::filesystem::is_directory(arg)) {
      std::vector<std::filesystem::path> paths;
      for (const auto& e : std::filesystem::recursive_directory_iterator(arg)) {
        if (e.is_regular_file()) paths.push_back(e.path());
      }
      std::sort(paths.begin(), paths.end());
      for (const auto& p : paths) {
        replay(p);
        ++files;
      }
    } else if (std::filesystem::is_regular_file(arg)) {
      replay(arg);
      ++files;
    }
  }
  std::printf("%d input(s) replayed without a finding\n", files);
  return 0;
}
