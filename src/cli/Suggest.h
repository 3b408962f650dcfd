#pragma once
// "Did you mean": the closest of a list of valid names to a misspelt one, for every message that names something
// the command line or the content folder does not have (commands, options, entities, methods, knobs, scenarios).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace afb::cli {

/// The candidate nearest to `word` by edit distance (case-insensitive; a swap of two neighbouring letters counts
/// as one edit), when it is near enough to be a likely misspelling: at most 2 edits, or a third of the word's
/// length for longer words. Ties go to the earlier candidate. nullopt when none is that near.
std::optional<std::string> closestMatch(std::string_view word, const std::vector<std::string>& candidates);

/// "; did you mean 'NAME'?" with closestMatch's answer, or an empty string when there is none.
std::string didYouMean(std::string_view word, const std::vector<std::string>& candidates);

/// "unknown WHAT 'WORD'; did you mean 'NAME'?", or, when no candidate is near, "unknown WHAT 'WORD' (A, B, ...)".
std::string unknownName(std::string_view what, std::string_view word, const std::vector<std::string>& candidates);

} // namespace afb::cli
