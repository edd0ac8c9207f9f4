// Checks of untrusted text: UTF-8 validity and control characters (case files, names read from
// mesh files), and a printable rendering of arbitrary bytes for error messages.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace cdem {

struct TextProblem {
  std::size_t offset = 0;  // byte offset of the first bad byte
  std::string what;  // e.g. "invalid UTF-8 (byte 0xff)", "a NUL byte", "control character U+0007"
};

// The first problem of `s` as text: invalid UTF-8 (overlong forms, surrogates and code points
// above U+10FFFF are invalid too), a NUL byte, or a control character (U+0001..U+001F, U+007F)
// other than tab, and other than line feed and carriage return when `multiline`.
std::optional<TextProblem> check_text(std::string_view s, bool multiline);

// `s` as printable ASCII for a message: other bytes as \xNN, cut to max_chars with "...".
std::string printable(std::string_view s, std::size_t max_chars = 40);

// 1-based line and column (in bytes) of a byte offset of `s`.
struct LineColumn {
  std::size_t line = 1, column = 1;
};
LineColumn line_column(std::string_view s, std::size_t offset);

}  // namespace cdem
