// What the files of the sample search share (sample_search*.cpp). Internal to src/motion.
#pragma once

#include <cstddef>
#include <limits>

namespace cncore::motion::sample_search_common {

inline constexpr double kRound = 1e-9;            // mm of rounding allowed on a step's range
inline constexpr std::size_t kCoalesceEvery = 8;  // cycles between searches for the commit point
inline constexpr double kInf = std::numeric_limits<double>::infinity();
// The beam keeps two classes of states, each K per speed bin: those that pass the guide with
// its sharp-corner term and those that pass it only without (see can_brake()).
inline constexpr std::size_t kClasses = 2;

}  // namespace cncore::motion::sample_search_common
