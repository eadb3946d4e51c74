// The execution-data buffer's seek() against the plain walk it replaces, for every hint.
#include "planner/buffer.hpp"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <cstdint>
#include <vector>

#include "planner/segment.hpp"

namespace cncore::planner {
namespace {

// "Skip j while pos ≥ end_mm(j) and j has a successor (and j < last)", one item at a time.
std::uint64_t walk(const SegmentBuffer& buf, std::uint64_t from, double pos_mm,
                   std::uint64_t last) {
  std::uint64_t j = from;
  while (j + 1 < buf.end_index() && j < last && pos_mm >= buf[j].end_mm()) ++j;
  return j;
}

// A ring that has wrapped: items of random lengths (0 included: events sit between motions),
// some of them not motion items.
RC_GTEST_PROP(SegmentBuffer, SeekFindsWhatTheWalkFindsFromAnyHint, ()) {
  const auto cap = *rc::gen::inRange<std::size_t>(1, 60);
  const auto pushed = *rc::gen::inRange<std::size_t>(1, 3 * cap);
  SegmentBuffer buf(cap);
  double s = 0;
  for (std::size_t k = 0; k < pushed; ++k) {
    if (buf.full()) buf.pop_front();
    Segment seg;
    seg.kind = *rc::gen::inRange(0, 4) == 0 ? ItemKind::kDwell : ItemKind::kMotion;
    seg.s0_mm = s;
    seg.length_mm = seg.kind == ItemKind::kMotion ? 0.25 * *rc::gen::inRange(0, 5) : 0.0;
    s = seg.end_mm();
    buf.push(seg);
  }
  for (std::uint64_t j = buf.begin_index(); j < buf.end_index(); ++j) {
    RC_ASSERT(buf.is_motion(j) == (buf[j].kind == ItemKind::kMotion));
    RC_ASSERT(buf.end_mm_of(j) == buf[j].end_mm());
  }
  for (int q = 0; q < 20; ++q) {
    const std::uint64_t from = buf.begin_index() + *rc::gen::inRange<std::uint64_t>(0, buf.size());
    const double pos = 0.125 * *rc::gen::inRange(-2, static_cast<int>(8 * s) + 3);
    const std::uint64_t last =
        *rc::gen::element<int>(0, 1) == 0
            ? UINT64_MAX
            : from + *rc::gen::inRange<std::uint64_t>(0, buf.end_index() - from + 2);
    const std::uint64_t hint = *rc::gen::inRange<std::uint64_t>(0, buf.end_index() + 3);
    RC_ASSERT(buf.seek(from, pos, last, hint) == walk(buf, from, pos, last));
    RC_ASSERT(buf.seek(from, pos, last) == walk(buf, from, pos, last));
  }
}

}  // namespace
}  // namespace cncore::planner
