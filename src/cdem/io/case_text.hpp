// Checks of a case file's text before the TOML parser sees it (toml11 3.7.1 reads past the end
// of its buffer on invalid UTF-8 in a quoted key, and recurses once per nesting level):
// valid UTF-8, no NUL bytes or other control characters than tab, line feed and carriage return
// (TOML allows no others), at most kMaxCaseFileBytes, at most kMaxTomlNesting levels of nested
// arrays and inline tables, and dotted keys (keys, table headers, keys of inline tables) of at
// most kMaxKeyParts parts (each part is a level of nested tables in toml11).
#pragma once
#include <cstddef>
#include <string>
#include <string_view>

namespace cdem {

inline constexpr int kMaxTomlNesting = 16;
inline constexpr int kMaxKeyParts = 64;

// Throws InputError "<name>: line L, column C: <problem>" for the first problem of `text`.
void check_case_text(std::string_view text, const std::string& name);

// The same for one --set override ("key=value"), which must hold no line breaks; at most 64 KiB.
void check_override_text(std::string_view text);

}  // namespace cdem
