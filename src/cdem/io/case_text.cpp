#include "cdem/io/case_text.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "cdem/core/error.hpp"
#include "cdem/core/input_file.hpp"
#include "cdem/core/text.hpp"

namespace cdem {
namespace {

// The deepest nesting of [ ] and { } outside strings and comments, and where it passes `limit`
// (npos if never). Table headers ([a], [[a]]) count like arrays; that is within the limit.
std::size_t nesting_over(std::string_view s, int limit) {
  int depth = 0;
  const std::size_t n = s.size();
  std::size_t i = 0;
  auto starts = [&](std::size_t at, std::string_view what) {
    return s.substr(at, what.size()) == what;
  };
  while (i < n) {
    const char c = s[i];
    if (c == '#') {
      while (i < n && s[i] != '\n') ++i;
    } else if (c == '"' || c == '\'') {
      const bool basic = c == '"';
      const std::string_view triple = basic ? "\"\"\"" : "'''";
      if (starts(i, triple)) {  // multi-line string: up to the closing triple quote
        i += 3;
        while (i < n && !starts(i, triple)) i += basic && s[i] == '\\' ? 2 : 1;
        i += 3;
        while (i < n && s[i] == c) ++i;  // up to two quotes may close the content
      } else {                           // one-line string: up to the quote or the line's end
        ++i;
        while (i < n && s[i] != c && s[i] != '\n') i += basic && s[i] == '\\' ? 2 : 1;
        ++i;
      }
      continue;
    } else if (c == '[' || c == '{') {
      if (++depth > limit) return i;
    } else if (c == ']' || c == '}') {
      depth = std::max(0, depth - 1);
    }
    ++i;
  }
  return std::string_view::npos;
}

}  // namespace

void check_case_text(std::string_view text, const std::string& name) {
  auto fail = [&](std::size_t offset, const std::string& what) -> void {
    const LineColumn lc = line_column(text, offset);
    throw InputError(fmt::format("{}: line {}, column {}: {}", name, lc.line, lc.column, what));
  };
  if (text.size() > kMaxCaseFileBytes)
    throw InputError(fmt::format("{}: {} bytes, more than the {} a case file may hold", name,
                                 text.size(), kMaxCaseFileBytes));
  if (const auto bad = check_text(text, true))
    fail(bad->offset, fmt::format("{} (a case file is UTF-8 text)", bad->what));
  if (const std::size_t at = nesting_over(text, kMaxTomlNesting); at != std::string_view::npos)
    fail(at, fmt::format("arrays or inline tables nested more than {} deep", kMaxTomlNesting));
}

void check_override_text(std::string_view text) {
  const std::string shown = printable(text, 60);
  if (text.size() > (64u << 10))
    throw InputError(fmt::format("--set '{}': {} bytes, more than the 64 KiB an override may hold",
                                 shown, text.size()));
  if (const auto bad = check_text(text, false))
    throw InputError(
        fmt::format("--set '{}': {} at byte {} (an override is one line of UTF-8 "
                    "text)",
                    shown, bad->what, bad->offset + 1));
  if (nesting_over(text, kMaxTomlNesting) != std::string_view::npos)
    throw InputError(fmt::format("--set '{}': arrays or inline tables nested more than {} deep",
                                 shown, kMaxTomlNesting));
}

}  // namespace cdem
