// "Did you mean …?" for a misspelled command or option: the closest known name by edit distance.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncore::app {

// Optimal-string-alignment distance: insertions, deletions, substitutions and transpositions of
// two neighbouring characters (the usual typing slips) each cost 1.
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate closest to `word`, if it is close enough to be what was meant: at most a third of
// the word's length in edits (at least 1, at most 3). Ties go to the first candidate.
std::optional<std::string> closest_name(std::string_view word,
                                        const std::vector<std::string>& candidates);

}  // namespace cncore::app
