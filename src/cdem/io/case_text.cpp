#include "cdem/io/case_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/core/input_file.hpp"
#include "cdem/core/text.hpp"

namespace cdem {
namespace {

constexpr int kMaxBinaryDigits = 62;

struct Structure {
  std::size_t offset = std::string_view::npos;  // where a limit is passed (npos: never)
  std::string what;
};

// The structure of TOML text, outside strings and comments: nesting of arrays and inline tables
// (values), and the parts of each dotted key (a key before '=', a table header, a key inside an
// inline table). toml11 recurses once per level of either, and a dotted key of 100 000 parts
// overflows the stack. Also the length of binary integers (below). Conservative: it only has
// to find where a limit is passed.
Structure scan_structure(std::string_view s, int max_depth, int max_parts) {
  const std::size_t n = s.size();
  std::vector<char> open;  // '[' (array) or '{' (inline table) of the values being read
  bool key = true;         // reading a key (line start at top level, or inside an inline table)
  bool header = false;     // reading a table header [a.b] or [[a.b]]
  bool blank = true;       // only whitespace so far on this line
  int parts = 1;
  auto starts = [&](std::size_t at, std::string_view what) {
    return s.substr(at, what.size()) == what;
  };
  auto new_key = [&] {
    key = true;
    parts = 1;
  };
  std::size_t i = 0;
  while (i < n) {
    const char c = s[i];
    if (c == '#') {
      while (i < n && s[i] != '\n') ++i;
      continue;
    }
    if (c == '\n') {
      if (open.empty()) {
        new_key();
        header = false;
      }
      blank = true;
      ++i;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    const bool at_line_start = blank;
    blank = false;
    if (c == '"' || c == '\'') {  // a string (or a quoted key part): skipped whole
      const bool basic = c == '"';
      const std::string_view triple = basic ? "\"\"\"" : "'''";
      if (starts(i, triple)) {
        i += 3;
        while (i < n && !starts(i, triple)) i += basic && s[i] == '\\' ? 2 : 1;
        i += 3;
        while (i < n && s[i] == c) ++i;
      } else {
        ++i;
        while (i < n && s[i] != c && s[i] != '\n') i += basic && s[i] == '\\' ? 2 : 1;
        ++i;
      }
      continue;
    }
    if (key || header) {
      if (c == '.' && ++parts > max_parts)
        return {i, fmt::format("a dotted key of more than {} parts", max_parts)};
      if (header && c == ']') {
        header = key = false;
      } else if (!header && c == '=') {
        key = false;
      } else if (key && !header && c == '[' && at_line_start && open.empty()) {
        header = true;
        parts = 1;
      } else if (key && c == '}' && !open.empty()) {  // an empty inline table {}
        open.pop_back();
        key = false;
      }
      ++i;
      continue;
    }
    // A binary integer: toml11 doubles a signed 64-bit place value at each digit, leading zeros
    // included, so a 63rd digit overflows it (undefined behaviour, found by fuzzing). An integer
    // is 64-bit anyway: more than 62 digits are refused here. (Octal and hexadecimal integers go
    // through a stream, which reports an overflow.)
    if (c == '0' && i + 1 < n && s[i + 1] == 'b' &&
        (i == 0 || !(std::isalnum(static_cast<unsigned char>(s[i - 1])) || s[i - 1] == '_' || s[i - 1] == '.'))) {
      std::size_t j = i + 2;
      int digits = 0;
      for (; j < n && (s[j] == '0' || s[j] == '1' || s[j] == '_'); ++j) digits += s[j] != '_';
      if (digits > kMaxBinaryDigits)
        return {i, fmt::format("a binary integer of more than {} digits", kMaxBinaryDigits)};
      i = j;
      continue;
    }
    if (c == '[' || c == '{') {
      open.push_back(c);
      if (static_cast<int>(open.size()) > max_depth)
        return {i, fmt::format("arrays or inline tables nested more than {} deep", max_depth)};
      if (c == '{') new_key();
    } else if (c == ']' || c == '}') {
      if (!open.empty()) open.pop_back();
    } else if (c == ',' && !open.empty() && open.back() == '{') {
      new_key();
    }
    ++i;
  }
  return {};
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
  if (const Structure st = scan_structure(text, kMaxTomlNesting, kMaxKeyParts);
      st.offset != std::string_view::npos)
    fail(st.offset, st.what);
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
  // The value is parsed as "v = <value>"; the key path is split on dots (at most kMaxKeyParts).
  const std::size_t eq = text.find('=');
  const std::string_view value = eq == std::string_view::npos ? "" : text.substr(eq + 1);
  if (const Structure st =
          scan_structure(std::string("v = ") + std::string(value), kMaxTomlNesting, kMaxKeyParts);
      st.offset != std::string_view::npos)
    throw InputError(fmt::format("--set '{}': {}", shown, st.what));
  const std::string_view key = text.substr(0, eq == std::string_view::npos ? text.size() : eq);
  if (std::count(key.begin(), key.end(), '.') >= kMaxKeyParts)
    throw InputError(
        fmt::format("--set '{}': a key path of more than {} parts", shown, kMaxKeyParts));
}

}  // namespace cdem
