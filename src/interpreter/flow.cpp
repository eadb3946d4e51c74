// Flow control: O-word subroutines, conditionals and loops (LinuxCNC), and Fanuc-style
// M98/M99 subprograms. The program is streamed, so flow is done by seeking the reader:
//   - "oN sub" records where the body starts and skips to "oN endsub";
//   - "oN call" seeks to the body (scanning forward for a sub defined later) and pushes a
//     frame holding the position to return to;
//   - loops remember the position of their head and seek back to it;
//   - a false condition, "break" or "else" skips forward to the matching O-word line.
// Only the subroutine table, the call frames and the open loops are kept in memory.
#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {

struct KeywordName {
  std::string_view text;
  OKeyword keyword;
};
// Longest first where one keyword is a prefix of another ("endsub" before "end…", "elseif"
// before "else").
constexpr KeywordName kKeywords[] = {
    {"endsub", OKeyword::kEndSub},
    {"endwhile", OKeyword::kEndWhile},
    {"endrepeat", OKeyword::kEndRepeat},
    {"endif", OKeyword::kEndIf},
    {"elseif", OKeyword::kElseIf},
    {"else", OKeyword::kElse},
    {"sub", OKeyword::kSub},
    {"call", OKeyword::kCall},
    {"return", OKeyword::kReturn},
    {"if", OKeyword::kIf},
    {"while", OKeyword::kWhile},
    {"do", OKeyword::kDo},
    {"repeat", OKeyword::kRepeat},
    {"break", OKeyword::kBreak},
    {"continue", OKeyword::kContinue},
};

const char* keyword_text(OKeyword k) {
  for (const auto& kw : kKeywords) {
    if (kw.keyword == k) return kw.text.data();
  }
  return "";
}

// The end of a parameter reference or bracketed expression at t[pos] ('#' or '['), found
// without evaluating it (the lines skipped over are never evaluated).
std::size_t skip_value(const std::string& t, std::size_t pos) {
  while (pos < t.size() && t[pos] == '#') ++pos;
  if (pos >= t.size()) return pos;
  if (t[pos] == '<') {
    const std::size_t close = t.find('>', pos);
    return close == std::string::npos ? t.size() : close + 1;
  }
  if (t[pos] == '[') {
    int depth = 0;
    for (; pos < t.size(); ++pos) {
      if (t[pos] == '[') ++depth;
      if (t[pos] == ']' && --depth == 0) return pos + 1;
    }
    return pos;
  }
  while (pos < t.size() && (is_digit(t[pos]) || t[pos] == '.')) ++pos;
  return pos;
}

std::string display(const std::string& label) {
  return "o" + printable(label);
}

}  // namespace

// Parses "[N…]oLABEL keyword" at the start of line_. Returns false when the line does not
// start with an O word (used while skipping).
bool Interpreter::Impl::parse_oword(OWord& o, bool evaluate) const {
  const std::string& t = line_.text;
  std::size_t pos = 0;
  if (!t.empty() && t[0] == 'n') {
    ++pos;
    while (pos < t.size() && (is_digit(t[pos]) || t[pos] == '.')) ++pos;
  }
  if (pos >= t.size() || t[pos] != 'o') return false;
  o.col = line_.col(pos);
  ++pos;
  o.label.clear();
  std::size_t computed = std::string::npos;  // "o[#1+2] call", "o#<n> call": where it starts
  if (pos < t.size() && (t[pos] == '[' || t[pos] == '#')) {
    computed = pos;
    pos = skip_value(t, pos);
    o.label = t.substr(computed, pos - computed);
  } else if (pos < t.size() && t[pos] == '<') {
    const std::size_t close = t.find('>', pos);
    if (close == std::string::npos) fail(o.col, "O word name without closing '>'");
    o.label = t.substr(pos, close - pos + 1);
    pos = close + 1;
  } else {
    const std::size_t start = pos;
    while (pos < t.size() && is_digit(t[pos])) ++pos;
    if (pos == start) fail(o.col, "O word without a number or <name>");
    // o100 and O0100 are the same label.
    std::size_t nz = start;
    while (nz + 1 < pos && t[nz] == '0') ++nz;
    o.label = t.substr(nz, pos - nz);
  }
  o.keyword = OKeyword::kNone;
  for (const auto& kw : kKeywords) {
    if (t.compare(pos, kw.text.size(), kw.text) == 0) {
      o.keyword = kw.keyword;
      pos += kw.text.size();
      break;
    }
  }
  if (o.keyword == OKeyword::kNone && pos < t.size()) {
    fail(line_.col(pos), "unknown O-word keyword '" + printable(t.substr(pos)) + "'");
  }
  // Keywords that take no value must end the line.
  switch (o.keyword) {
    case OKeyword::kSub:
    case OKeyword::kElse:
    case OKeyword::kEndIf:
    case OKeyword::kEndWhile:
    case OKeyword::kDo:
    case OKeyword::kEndRepeat:
    case OKeyword::kBreak:
    case OKeyword::kContinue:
      if (pos < t.size()) {
        fail(line_.col(pos), fmt::format("unexpected '{}' after o{} {}", printable(t.substr(pos)),
                                         printable(o.label), keyword_text(o.keyword)));
      }
      break;
    default:
      break;
  }
  o.args = pos;
  if (computed != std::string::npos && evaluate) {
    if (o.keyword != OKeyword::kCall) fail(o.col, "a computed O number is allowed only with call");
    std::size_t p = computed;
    Evaluator eval(line_, ctx_, params_);
    const double v = eval.real_value(p);
    if (v < 0 || v != std::floor(v) || v > 1e9) {
      fail(line_.col(computed), fmt::format("O number {} is not a program number", v));
    }
    o.label = fmt::format("{}", static_cast<long long>(v));
  }
  return true;
}

// The bracketed condition after if/elseif/while.
double Interpreter::Impl::condition(const OWord& o) {
  std::size_t pos = o.args;
  if (pos >= line_.text.size() || line_.text[pos] != '[') {
    fail(line_.col(pos),
         fmt::format("{} {} needs a condition [ … ]", display(o.label), keyword_text(o.keyword)));
  }
  Evaluator eval(line_, ctx_, params_);
  const double v = eval.real_value(pos);
  if (pos < line_.text.size()) fail(line_.col(pos), "unexpected text after the condition");
  return v;
}

void Interpreter::Impl::loop_limit(const Loop& loop) const {
  throw InputError(file_, loop.line, loop.col,
                   fmt::format("runaway loop: {} ran more than max_loop_iterations ({}) times",
                               display(loop.label), machine_.max_loop_iterations));
}

void Interpreter::Impl::count_iteration(Loop& loop) {
  if (++loop.iterations >= machine_.max_loop_iterations) loop_limit(loop);
  spend(loop.line, loop.col);
}

// Nested loops and calls multiply: each may stay under max_loop_iterations while the program
// as a whole never ends. Every pass and call spends from one budget for the whole program.
void Interpreter::Impl::spend(std::uint32_t line, std::uint32_t col) {
  if (++passes_ <= machine_.max_total_iterations) return;
  throw InputError(file_, line, col,
                   fmt::format("runaway program: loops and calls made more than "
                               "max_total_iterations ({}) passes in all",
                               machine_.max_total_iterations));
}

// Reads forward to the next line that starts with an O word, without executing the lines in
// between; line_ holds it and `o` its O word. False at the end of the file.
bool Interpreter::Impl::next_oword(OWord& o) {
  std::string_view raw;
  while (reader_->next(raw)) {
    ctx_.line = reader_->current().line;
    normalize_line(raw, line_, ctx_);
    if (!skipped() && !line_.text.empty() && parse_oword(o)) return true;
  }
  return false;
}

// Reads forward to the O-word line with label `from.label` and one of `stops`, leaving line_
// holding it. Lines in between are not executed.
OKeyword Interpreter::Impl::skip_to(const OWord& from, std::initializer_list<OKeyword> stops,
                                    const char* what) {
  const std::uint32_t line = ctx_.line;
  const std::uint32_t col = from.col;
  OWord o;
  while (next_oword(o)) {
    if (o.label != from.label) continue;
    for (OKeyword k : stops) {
      if (o.keyword == k) return k;
    }
  }
  throw InputError(file_, line, col,
                   fmt::format("{} {} has no matching {}", display(from.label),
                               keyword_text(from.keyword), what));
}

// Skips the body of a Fanuc subprogram ("O1000" … "M99").
void Interpreter::Impl::skip_fanuc_sub(std::uint32_t def_line) {
  std::string_view raw;
  while (reader_->next(raw)) {
    ctx_.line = reader_->current().line;
    normalize_line(raw, line_, ctx_);
    const std::string& t = line_.text;
    for (std::size_t p = t.find("m99"); p != std::string::npos; p = t.find("m99", p + 1)) {
      if (p + 3 >= t.size() || !is_digit(t[p + 3])) return;
    }
  }
  throw InputError(file_, def_line, 1, "subprogram has no M99");
}

// The subroutine `key`, scanning forward (and recording every definition met) when it has not
// been seen yet. Keys: "100", "<name>" for O-word subs; "F1000" for Fanuc subprograms.
const SubDef* Interpreter::Impl::find_sub(const std::string& key, std::uint32_t col) {
  if (auto it = subs_.find(key); it != subs_.end()) return &it->second;
  // A subroutine's own file holds that subroutine only, and streamed lines cannot be read
  // ahead: there, a subroutine not met yet can only come from its file.
  if (source_ == 0 && !reader_->is_pulled()) {
    if (const SubDef* def = scan_for_sub(key)) return def;
  }
  if (!key.empty() && key[0] == '<') {
    if (const SubDef* def = load_sub_file(key, col)) return def;
  }
  const bool fanuc = !key.empty() && key[0] == 'F';
  throw InputError(
      file_, ctx_.line, col,
      fanuc ? fmt::format("subprogram O{} is not defined in this file", key.substr(1))
      : key[0] == '<'
          ? fmt::format("subroutine {} is not defined in this file, and no {}.ngc is in the "
                        "program's folder or on the subroutine path",
                        display(key), printable(key.substr(1, key.size() - 2)))
          : fmt::format("subroutine {} is not defined in this file", display(key)));
}

// Reads ahead in the program for `key`, recording every definition met; back where it was
// when the program does not define it.
const SubDef* Interpreter::Impl::scan_for_sub(const std::string& key) {
  const std::uint32_t line = ctx_.line;
  const LinePos resume = reader_->following();
  OWord o;
  while (next_oword(o)) {
    std::string k;
    if (o.keyword == OKeyword::kSub) {
      k = o.label;
    } else if (o.keyword == OKeyword::kNone) {
      k = "F" + o.label;
    } else {
      continue;
    }
    auto [it, inserted] = subs_.try_emplace(k, SubDef{reader_->following(), ctx_.line, source_});
    if (k == key) return &it->second;
  }
  reader_->seek(resume);
  ctx_.line = line;
  return nullptr;
}

void Interpreter::Impl::execute_oword(const OWord& o) {
  words_.first_col = o.col;
  switch (o.keyword) {
    case OKeyword::kNone: {
      // Fanuc program number. One met before the program has produced anything (only
      // comments, parameters or modes before it) names the main program; later ones start
      // subprograms (called with M98), which are skipped when reached in sequence.
      if (!produced_ && frames_.empty() && !main_titled_) {
        main_titled_ = true;
        return;
      }
      subs_.try_emplace("F" + o.label, SubDef{reader_->following(), ctx_.line, source_});
      skip_fanuc_sub(ctx_.line);
      return;
    }
    case OKeyword::kSub: {
      if (!frames_.empty() && !frames_.back().fanuc && frames_.back().label == o.label) {
        fail(o.col, fmt::format("{} sub defined inside itself", display(o.label)));
      }
      if (source_ != 0) {
        fail(o.col, fmt::format("{} sub in the file of {}: a subroutine's file defines that "
                                "subroutine only",
                                display(o.label), display(frames_.back().label)));
      }
      subs_.try_emplace(o.label, SubDef{reader_->following(), ctx_.line, source_});
      skip_to(o, {OKeyword::kEndSub}, "endsub");
      return;
    }
    case OKeyword::kEndSub:
    case OKeyword::kReturn:
      return_from_sub(o);
      return;
    case OKeyword::kCall:
      call_sub(o);
      return;
    case OKeyword::kIf:
      run_if(o);
      return;
    case OKeyword::kElseIf:
    case OKeyword::kElse:
      skip_to(o, {OKeyword::kEndIf}, "endif");
      return;
    case OKeyword::kEndIf:
      return;
    case OKeyword::kWhile:
      run_while(o);
      return;
    case OKeyword::kEndWhile: {
      if (loops_.empty() || loops_.back().label != o.label ||
          loops_.back().kind != Loop::Kind::kWhile) {
        fail(o.col, fmt::format("{} endwhile without while", display(o.label)));
      }
      reader_->seek(loops_.back().head);
      return;
    }
    case OKeyword::kDo: {
      Loop l;
      l.label = o.label;
      l.kind = Loop::Kind::kDo;
      l.head = reader_->following();
      l.line = ctx_.line;
      l.col = o.col;
      loops_.push_back(l);
      return;
    }
    case OKeyword::kRepeat:
      run_repeat(o);
      return;
    case OKeyword::kEndRepeat:
      end_repeat(o);
      return;
    case OKeyword::kBreak:
    case OKeyword::kContinue:
      leave_loop(o);
      return;
  }
}

// endsub / return: back to the caller, with an optional [value] in #<_value> (0 without one).
// LinuxCNC takes a `return` under any label inside a subroutine (o110 return in o110 if).
void Interpreter::Impl::return_from_sub(const OWord& o) {
  const bool any_label = o.keyword == OKeyword::kReturn;
  if (frames_.empty() || frames_.back().fanuc || (!any_label && frames_.back().label != o.label)) {
    fail(o.col, fmt::format("{} {} outside a call of {}", display(o.label), keyword_text(o.keyword),
                            display(o.label)));
  }
  std::size_t pos = o.args;
  if (pos < line_.text.size()) {
    Evaluator eval(line_, ctx_, params_);
    const double v = eval.real_value(pos);
    params_.set_named("_value", v);
    params_.set_named("_value_returned", 1);
  } else {
    params_.set_named("_value", 0);
    params_.set_named("_value_returned", 0);
  }
  const Frame f = frames_.back();
  frames_.pop_back();
  loops_.resize(f.loop_depth);
  params_.pop_scope();
  enter(f.return_source, f.return_to);
}

// o<name> call [e1] [e2] …: the arguments become #1, #2, … of the new scope.
void Interpreter::Impl::call_sub(const OWord& o) {
  std::array<double, Parameters::kArgCount> args{};
  std::size_t pos = o.args;
  std::size_t n = 0;
  Evaluator eval(line_, ctx_, params_);
  while (pos < line_.text.size()) {
    if (n >= args.size()) fail(line_.col(pos), "more than 30 subroutine arguments");
    args[n++] = eval.real_value(pos);
  }
  if (frames_.size() >= machine_.max_call_depth) {
    fail(o.col, fmt::format("call of {} exceeds max_call_depth ({})", display(o.label),
                            machine_.max_call_depth));
  }
  spend(ctx_.line, o.col);
  Frame f;
  f.label = o.label;
  f.return_to = reader_->following();
  f.return_source = source_;
  f.loop_depth = loops_.size();
  f.line = ctx_.line;
  f.col = o.col;
  const SubDef* def = find_sub(o.label, o.col);
  f.def_line = def->line;
  f.body = def->body;
  frames_.push_back(f);
  params_.push_scope(args);
  params_.set_named("_value_returned", 0);
  enter(def->source, def->body);
}

// if / elseif / else: run the first branch whose condition holds; "elseif"/"else" met
// while running a branch skip to "endif".
void Interpreter::Impl::run_if(const OWord& o) {
  OWord cur = o;
  double cond = condition(cur);
  while (cond == 0) {
    const OKeyword k = skip_to(o, {OKeyword::kElseIf, OKeyword::kElse, OKeyword::kEndIf}, "endif");
    if (k != OKeyword::kElseIf) return;
    parse_oword(cur);
    cond = condition(cur);
  }
}

// while: the head of a while loop, or the end of a do … while loop.
void Interpreter::Impl::run_while(const OWord& o) {
  Loop* top = loops_.empty() ? nullptr : &loops_.back();
  if (top != nullptr && top->label == o.label && top->kind == Loop::Kind::kDo) {
    // The end of a do … while loop.
    if (condition(o) != 0) {
      count_iteration(*top);
      reader_->seek(top->head);
    } else {
      loops_.pop_back();
    }
    return;
  }
  if (top != nullptr && top->label == o.label && top->kind == Loop::Kind::kWhile &&
      top->head.offset == reader_->current().offset) {
    count_iteration(*top);  // back at the head after endwhile or continue
  } else {
    Loop l;
    l.label = o.label;
    l.kind = Loop::Kind::kWhile;
    l.head = reader_->current();
    l.line = ctx_.line;
    l.col = o.col;
    loops_.push_back(l);
  }
  if (condition(o) == 0) {
    loops_.pop_back();
    skip_to(o, {OKeyword::kEndWhile}, "endwhile");
  }
}

// repeat [count]: the head of a counted loop.
void Interpreter::Impl::run_repeat(const OWord& o) {
  std::size_t pos = o.args;
  if (pos >= line_.text.size()) fail(o.col, "repeat needs a count [ … ]");
  Evaluator eval(line_, ctx_, params_);
  const double count = std::round(eval.real_value(pos));
  Loop l;
  l.label = o.label;
  l.kind = Loop::Kind::kRepeat;
  l.head = reader_->following();
  l.remaining = count;
  l.line = ctx_.line;
  l.col = o.col;
  if (count >= static_cast<double>(machine_.max_loop_iterations)) loop_limit(l);
  if (count <= 0) {
    skip_to(o, {OKeyword::kEndRepeat}, "endrepeat");
    return;
  }
  loops_.push_back(l);
}

void Interpreter::Impl::end_repeat(const OWord& o) {
  if (loops_.empty() || loops_.back().label != o.label ||
      loops_.back().kind != Loop::Kind::kRepeat) {
    fail(o.col, fmt::format("{} endrepeat without repeat", display(o.label)));
  }
  Loop& l = loops_.back();
  count_iteration(l);
  l.remaining -= 1;
  if (l.remaining > 0) {
    reader_->seek(l.head);
  } else {
    loops_.pop_back();
  }
}

// break / continue of the innermost loop.
void Interpreter::Impl::leave_loop(const OWord& o) {
  if (loops_.empty() || loops_.back().label != o.label) {
    fail(o.col, fmt::format("{} {} outside its loop", display(o.label), keyword_text(o.keyword)));
  }
  const Loop::Kind kind = loops_.back().kind;
  const OKeyword close = kind == Loop::Kind::kWhile ? OKeyword::kEndWhile
                         : kind == Loop::Kind::kDo  ? OKeyword::kWhile
                                                    : OKeyword::kEndRepeat;
  const char* what = keyword_text(close);
  if (o.keyword == OKeyword::kBreak) {
    loops_.pop_back();
    skip_to(o, {close}, what);
    return;
  }
  // continue: go to the loop's closing line and run it (re-test, count, jump back).
  skip_to(o, {close}, what);
  OWord closing;
  parse_oword(closing);
  execute_oword(closing);
}

// M98 P<n> [L<count>]: call Fanuc subprogram O<n> (same parameter scope).
void Interpreter::Impl::call_fanuc(std::uint32_t col) {
  const Words& w = words_;
  if (!w.has('p')) fail(col, "M98 without P (subprogram number)");
  const double p = w['p'].value;
  if (p < 0 || p != std::floor(p) || p > 1e9) {
    fail(w['p'].col, "M98 P must be a program number");
  }
  double count = 1;
  if (w.has('l')) {
    count = w['l'].value;
    if (count < 0 || count != std::floor(count)) fail(w['l'].col, "M98 L must be a count");
    if (count >= static_cast<double>(machine_.max_loop_iterations)) {
      fail(w['l'].col, fmt::format("M98 L{} exceeds max_loop_iterations", count));
    }
  }
  if (count == 0) return;
  if (frames_.size() >= machine_.max_call_depth) {
    fail(col, fmt::format("M98 exceeds max_call_depth ({})", machine_.max_call_depth));
  }
  const std::string label = fmt::format("{}", static_cast<long long>(p));
  Frame f;
  f.label = label;
  f.fanuc = true;
  f.return_to = reader_->following();
  f.return_source = source_;
  f.loop_depth = loops_.size();
  f.line = ctx_.line;
  f.col = col;
  f.repeats_left = static_cast<std::uint64_t>(count);
  const SubDef* def = find_sub("F" + label, col);
  f.body = def->body;
  f.def_line = def->line;
  frames_.push_back(f);
  enter(def->source, def->body);
}

// M99: end of a Fanuc subprogram; repeat it while L count remains, else return.
void Interpreter::Impl::return_fanuc(std::uint32_t col) {
  if (frames_.empty() && main_titled_) {
    // The end of a main program "O1 … M99": a controller would start it again; like
    // LinuxCNC's rs274, cncore runs it once.
    finished_ = true;
    return;
  }
  if (frames_.empty() || !frames_.back().fanuc) {
    fail(col, "M99 outside an M98 subprogram (restarting the main program is not supported)");
  }
  Frame& f = frames_.back();
  loops_.resize(f.loop_depth);
  spend(f.line, f.col);
  if (--f.repeats_left > 0) {
    reader_->seek(f.body);
    return;
  }
  const LinePos back = f.return_to;
  const std::size_t source = f.return_source;
  frames_.pop_back();
  enter(source, back);
}

void Interpreter::Impl::end_of_file() {
  if (!loops_.empty()) {
    const Loop& l = loops_.back();
    const char* what = l.kind == Loop::Kind::kWhile ? "while has no matching endwhile"
                       : l.kind == Loop::Kind::kDo  ? "do has no matching while"
                                                    : "repeat has no matching endrepeat";
    throw InputError(file_, l.line, l.col, fmt::format("{} {}", display(l.label), what));
  }
  if (!frames_.empty()) {
    const Frame& f = frames_.back();
    throw InputError(file_, f.def_line, 1,
                     f.fanuc ? fmt::format("subprogram O{} has no M99", f.label)
                             : fmt::format("{} sub has no matching endsub", display(f.label)));
  }
  finished_ = true;
}

}  // namespace cncore::interp
