// Subroutines in files of their own, as LinuxCNC's SUBROUTINE_PATH: `o<name> call` of a
// subroutine the program does not define opens name.ngc from the program's folder or the
// subroutine path (the first found) and runs its "o<name> sub" … "o<name> endsub". The file
// stays open for later calls; its other lines are never run.
#include <fmt/format.h>

#include <filesystem>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

void Interpreter::Impl::enter(std::size_t source, LinePos pos) {
  if (source != source_) {
    source_ = source;
    reader_ = &sources_[source]->reader;
    file_ = sources_[source]->file;
    // The innermost call made from the program (frames_ already holds the call entering a
    // file, and no longer the one returning from it).
    for (auto f = frames_.rbegin(); source_ != 0 && f != frames_.rend(); ++f) {
      if (f->return_source == 0) {
        entry_line_ = f->line;
        entry_col_ = f->col;
        break;
      }
    }
  }
  reader_->seek(pos);
}

const SubDef* Interpreter::Impl::load_sub_file(const std::string& key, std::uint32_t col) {
  const std::string name = key.substr(1, key.size() - 2);  // "<name>": labels are lower case
  std::string path;
  for (const std::string& dir : sub_dirs_) {
    const std::filesystem::path p = std::filesystem::path(dir) / (name + ".ngc");
    std::error_code ec;
    if (std::filesystem::is_regular_file(p, ec)) {
      path = p.string();
      break;
    }
  }
  if (path.empty()) return nullptr;
  // Each file keeps a descriptor and a chunk buffer open until the program ends.
  constexpr std::size_t kMaxSubFiles = 256;
  if (sources_.size() > kMaxSubFiles) {
    throw InputError(
        file_, ctx_.line, col,
        fmt::format("{}: more than {} subroutine files in one program", path, kMaxSubFiles));
  }
  const std::uint32_t call_line = ctx_.line;
  const std::string caller = file_;
  const std::size_t caller_source = source_;
  const LinePos resume = reader_->following();
  sources_.push_back(std::make_unique<Source>(Source{LineReader::open_file(path), path}));
  const std::size_t source = sources_.size() - 1;
  enter(source, LinePos{});
  OWord o;
  while (next_oword(o)) {
    if (o.keyword == OKeyword::kSub && o.label == key) {
      const SubDef def{reader_->following(), ctx_.line, source};
      enter(caller_source, resume);
      return &subs_.try_emplace(key, def).first->second;
    }
  }
  enter(caller_source, resume);
  ctx_.line = call_line;
  throw InputError(caller, call_line, col,
                   fmt::format("{} has no \"o{} sub\" line", path, printable(key)));
}

}  // namespace cncore::interp
