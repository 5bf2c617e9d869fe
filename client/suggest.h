// "Did you mean ...?" for mistyped options and subcommands: the closest valid name by edit
// distance (optimal string alignment: a swap of two neighbouring letters, the commonest
// typo, costs 1 like an insertion, a deletion or a substitution).
#pragma once
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace vdbwrap::cli {

inline size_t edit_distance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  // Three rows: the transposition looks two rows back.
  std::vector<size_t> prev2(m + 1), prev(m + 1), cur(m + 1);
  for (size_t j = 0; j <= m; ++j) prev[j] = j;
  for (size_t i = 1; i <= n; ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= m; ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) cur[j] = std::min(cur[j], prev2[j - 2] + 1);
    }
    std::swap(prev2, prev);
    std::swap(prev, cur);
  }
  return prev[m];
}

// The candidate closest to word, when it is close enough to be a likely typo: at most a
// third of the word's letters wrong (at least 1, at most 3). Leading dashes are not letters;
// words under three letters get no suggestion (any letter is one edit from any other).
// Ties go to the earlier candidate.
inline std::optional<std::string> closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  auto bare = [](const std::string& s) { return s.substr(std::min(s.find_first_not_of('-'), s.size())); };
  const std::string w = bare(word);
  if (w.size() < 3) return std::nullopt;
  const size_t limit = std::clamp<size_t>(w.size() / 3, 1, 3);
  std::optional<std::string> best;
  size_t best_distance = limit + 1;
  for (const std::string& c : candidates) {
    const size_t d = edit_distance(w, bare(c));
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

}  // namespace vdbwrap::cli
