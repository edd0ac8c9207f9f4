#include "cdem/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>

namespace cdem {

std::optional<TextProblem> check_text(std::string_view s, bool multiline) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned char c = p[i];
    if (c < 0x80) {
      if (c == 0) return TextProblem{i, "a NUL byte"};
      const bool allowed = c == '\t' || (multiline && (c == '\n' || c == '\r'));
      if ((c < 0x20 || c == 0x7f) && !allowed)
        return TextProblem{i, fmt::format("control character U+{:04X}", c)};
      ++i;
      continue;
    }
    // Multi-byte sequences (RFC 3629): lead byte, its length and the range of the code point.
    std::size_t len = 0;
    std::uint32_t cp = 0, min = 0;
    if (c >= 0xc2 && c <= 0xdf) {
      len = 2, cp = c & 0x1fu, min = 0x80;
    } else if (c >= 0xe0 && c <= 0xef) {
      len = 3, cp = c & 0x0fu, min = 0x800;
    } else if (c >= 0xf0 && c <= 0xf4) {
      len = 4, cp = c & 0x07u, min = 0x10000;
    } else {
      return TextProblem{i, fmt::format("invalid UTF-8 (byte 0x{:02x})", c)};
    }
    if (n - i < len) return TextProblem{i, "invalid UTF-8 (a sequence cut short at the end)"};
    for (std::size_t k = 1; k < len; ++k) {
      const unsigned char d = p[i + k];
      if ((d & 0xc0u) != 0x80u)
        return TextProblem{i, fmt::format("invalid UTF-8 (byte 0x{:02x} after 0x{:02x})", d, c)};
      cp = (cp << 6) | (d & 0x3fu);
    }
    if (cp < min) return TextProblem{i, "invalid UTF-8 (an overlong form)"};
    if (cp >= 0xd800 && cp <= 0xdfff) return TextProblem{i, "invalid UTF-8 (a surrogate)"};
    if (cp > 0x10ffff) return TextProblem{i, "invalid UTF-8 (beyond U+10FFFF)"};
    if (cp >= 0x80 && cp <= 0x9f)
      return TextProblem{i, fmt::format("control character U+{:04X}", cp)};
    i += len;
  }
  return std::nullopt;
}

std::string printable(std::string_view s, std::size_t max_chars) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\')
      out += static_cast<char>(c);
    else
      out += fmt::format("\\x{:02x}", c);
  }
  return out;
}

LineColumn line_column(std::string_view s, std::size_t offset) {
  offset = std::min(offset, s.size());
  LineColumn lc;
  const std::string_view head = s.substr(0, offset);
  lc.line = 1 + static_cast<std::size_t>(std::count(head.begin(), head.end(), '\n'));
  const std::size_t nl = head.rfind('\n');
  lc.column = nl == std::string_view::npos ? offset + 1 : offset - nl;
  return lc;
}

}  // namespace cdem
