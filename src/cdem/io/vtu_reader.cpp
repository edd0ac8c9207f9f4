// Reader of the project's VTU/PVD files: a small XML parser for the text head (elements,
// attributes, comments, processing instructions; no DTD or CDATA) that stops after the
// <AppendedData> start tag, the array decoder of the appended raw section (plain or zlib
// blocks), and the consistency checks described in vtu_reader.hpp.
#include "cdem/io/vtu_reader.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <type_traits>

namespace cdem {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the VTU reader decodes LittleEndian files by copying bytes");

struct XmlElement {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<XmlElement> children;

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes)
      if (k == key) return &v;
    return nullptr;
  }
};

// An error in file `where`.
[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::runtime_error(fmt::format("invalid VTK file '{}': {}", where, what));
}

// A minimal non-validating XML parser over the whole file; it can stop after a given start
// tag (the appended binary data follows it) and resume after the binary section.
class XmlParser {
 public:
  XmlParser(std::string_view text, std::string where) : text_(text), where_(std::move(where)) {}

  // Parses from the current position. Returns true right after the start tag of an element
  // named `stop` (which stays open; position() is just after its '>'), false when the
  // document ended properly (root closed, then only white space, comments or declarations).
  bool run(std::string_view stop = {}) {
    while (true) {
      if (pos_ >= text_.size()) {
        if (!open_.empty())
          error(fmt::format("the file ends inside <{}> (truncated?)", open_.back().name));
        if (!root_done_) error("no root element");
        return false;
      }
      if (text_[pos_] != '<') {
        const std::size_t next = std::min(text_.find('<', pos_), text_.size());
        if (open_.empty() &&
            text_.substr(pos_, next - pos_).find_first_not_of(" \t\r\n") != std::string_view::npos)
          error("text outside the root element");
        pos_ = next;
        continue;
      }
      if (starts_with("<?")) {
        skip_past("?>", "processing instruction");
      } else if (starts_with("<!--")) {
        skip_past("-->", "comment");
      } else if (starts_with("<!")) {
        error("DOCTYPE and CDATA sections are not supported");
      } else if (starts_with("</")) {
        end_tag();
      } else if (start_tag(stop)) {
        return true;
      }
    }
  }

  std::size_t position() const { return pos_; }
  void seek(std::size_t pos) { pos_ = pos; }
  // The open elements, outermost first (after run() returned true).
  const std::vector<XmlElement>& open_elements() const { return open_; }
  const XmlElement& root() const { return root_; }
  [[noreturn]] void error(const std::string& what) const {
    fail(where_, fmt::format("malformed XML at byte {}: {}", pos_, what));
  }

 private:
  bool starts_with(std::string_view s) const { return text_.substr(pos_).starts_with(s); }
  void skip_past(std::string_view end, const char* what) {
    const std::size_t at = text_.find(end, pos_);
    if (at == std::string_view::npos) error(fmt::format("unterminated {} (truncated?)", what));
    pos_ = at + end.size();
  }
  static bool name_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '-' ||
           c == '.' || static_cast<unsigned char>(c) >= 0x80;
  }
  void skip_space() {
    while (pos_ < text_.size() && std::strchr(" \t\r\n", text_[pos_]) && text_[pos_] != '\0')
      ++pos_;
  }
  char peek() const {
    if (pos_ >= text_.size()) error("the file ends inside a tag (truncated?)");
    return text_[pos_];
  }
  std::string name() {
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && name_char(text_[pos_])) ++pos_;
    if (pos_ == begin || std::isdigit(static_cast<unsigned char>(text_[begin])) ||
        text_[begin] == '-' || text_[begin] == '.') {
      pos_ = begin;
      error("expected a name");
    }
    return std::string(text_.substr(begin, pos_ - begin));
  }
  std::string unescape(std::string_view raw) const {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '&') {
        out += raw[i];
        continue;
      }
      const std::size_t semi = raw.find(';', i);
      if (semi == std::string_view::npos) error("unterminated entity in an attribute");
      const std::string_view entity = raw.substr(i + 1, semi - i - 1);
      if (entity == "amp")
        out += '&';
      else if (entity == "lt")
        out += '<';
      else if (entity == "gt")
        out += '>';
      else if (entity == "quot")
        out += '"';
      else if (entity == "apos")
        out += '\'';
      else if (entity.size() >= 2 && entity[0] == '#') {
        const bool hex = entity[1] == 'x';
        unsigned code = 0;
        const char* first = entity.data() + (hex ? 2 : 1);
        const char* last = entity.data() + entity.size();
        const auto [ptr, ec] = std::from_chars(first, last, code, hex ? 16 : 10);
        if (ec != std::errc() || ptr != last || first == last || code == 0 || code > 0x10FFFF)
          error(fmt::format("bad character reference &{};", entity));
        append_utf8(out, code);
      } else {
        error(fmt::format("unknown entity &{};", entity));
      }
      i = semi;
    }
    return out;
  }
  static void append_utf8(std::string& out, unsigned code) {
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (code >> 18));
      out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
  }
  void end_tag() {
    pos_ += 2;
    const std::string tag = name();
    skip_space();
    if (peek() != '>') error(fmt::format("expected '>' to end </{}", tag));
    ++pos_;
    if (open_.empty()) error(fmt::format("end tag </{}> without a start tag", tag));
    if (open_.back().name != tag)
      error(fmt::format("end tag </{}> where </{}> was expected", tag, open_.back().name));
    XmlElement element = std::move(open_.back());
    open_.pop_back();
    close(std::move(element));
  }
  void close(XmlElement element) {
    if (open_.empty()) {
      root_ = std::move(element);
      root_done_ = true;
    } else {
      open_.back().children.push_back(std::move(element));
    }
  }
  // Returns true when the element is `stop` and stays open.
  bool start_tag(std::string_view stop) {
    if (root_done_ && open_.empty()) error("a second root element");
    ++pos_;
    XmlElement element;
    element.name = name();
    while (true) {
      const std::size_t before = pos_;
      skip_space();
      if (peek() == '>' || (peek() == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '>'))
        break;
      if (pos_ == before) error(fmt::format("expected white space in <{}>", element.name));
      std::string key = name();
      skip_space();
      if (peek() != '=') error(fmt::format("expected '=' after attribute {}", key));
      ++pos_;
      skip_space();
      const char quote = peek();
      if (quote != '"' && quote != '\'') error(fmt::format("attribute {} is not quoted", key));
      const std::size_t end = text_.find(quote, pos_ + 1);
      if (end == std::string_view::npos) error("unterminated attribute value (truncated?)");
      const std::string_view raw = text_.substr(pos_ + 1, end - pos_ - 1);
      if (raw.find('<') != std::string_view::npos) error("'<' in an attribute value");
      if (element.attribute(key)) error(fmt::format("attribute {} given twice", key));
      element.attributes.emplace_back(std::move(key), unescape(raw));
      pos_ = end + 1;
    }
    if (peek() == '/') {
      pos_ += 2;
      close(std::move(element));
      return false;
    }
    ++pos_;
    const bool stopped = !stop.empty() && element.name == stop;
    open_.push_back(std::move(element));
    return stopped;
  }

  std::string_view text_;
  std::string where_;
  std::size_t pos_ = 0;
  std::vector<XmlElement> open_;
  XmlElement root_;
  bool root_done_ = false;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("cannot open '{}' for reading", path));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0) throw std::runtime_error(fmt::format("cannot read '{}'", path));
  std::string text(static_cast<std::size_t>(size), '\0');
  if (!in.read(text.data(), size)) throw std::runtime_error(fmt::format("cannot read '{}'", path));
  return text;
}

const XmlElement& only_child(const std::string& where, const XmlElement& parent,
                             std::string_view name) {
  const XmlElement* found = nullptr;
  for (const XmlElement& c : parent.children) {
    if (c.name != name) continue;
    if (found)
      fail(where, fmt::format("more than one <{}> in <{}> (not supported)", name, parent.name));
    found = &c;
  }
  if (!found) fail(where, fmt::format("no <{}> in <{}>", name, parent.name));
  return *found;
}

const XmlElement* optional_child(const std::string& where, const XmlElement& parent,
                                 std::string_view name) {
  const auto n = std::count_if(parent.children.begin(), parent.children.end(),
                               [&](const XmlElement& c) { return c.name == name; });
  return n == 0 ? nullptr : &only_child(where, parent, name);
}

const std::string& required(const std::string& where, const XmlElement& e, std::string_view key) {
  const std::string* value = e.attribute(key);
  if (!value) fail(where, fmt::format("<{}> has no {} attribute", e.name, key));
  return *value;
}

std::int64_t parse_count(const std::string& where, const XmlElement& e, std::string_view key,
                         const std::string& text) {
  std::int64_t value = -1;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || text.empty() || value < 0)
    fail(where, fmt::format("<{}> {}=\"{}\" is not a non-negative integer", e.name, key, text));
  return value;
}

// Size in bytes of a VTK scalar type, 0 when unknown.
std::size_t type_size(std::string_view type) {
  if (type == "Int8" || type == "UInt8") return 1;
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int32" || type == "UInt32" || type == "Float32") return 4;
  if (type == "Int64" || type == "UInt64" || type == "Float64") return 8;
  return 0;
}
bool is_float(std::string_view type) { return type == "Float32" || type == "Float64"; }

template <class T>
T load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// The appended raw section and the way its arrays are encoded.
class Appended {
 public:
  Appended(std::string where, std::string_view text, std::size_t base, bool compressed,
           std::size_t header_size)
      : where_(std::move(where)),
        data_(reinterpret_cast<const unsigned char*>(text.data()) + base),
        size_(text.size() - base),
        compressed_(compressed),
        header_size_(header_size) {}

  // Decodes the array at `offset` that must hold exactly `expected` bytes.
  std::vector<unsigned char> decode(const std::string& label, std::uint64_t offset,
                                    std::uint64_t expected) {
    std::uint64_t pos = offset;
    const auto need = [&](std::uint64_t bytes, const char* what) {
      if (pos > size_ || bytes > size_ - pos)
        fail(where_,
             fmt::format("{}: the {} extends past the end of the file (truncated?)", label, what));
    };
    const auto word = [&](const char* what) {
      need(header_size_, what);
      const std::uint64_t w =
          header_size_ == 8 ? load<std::uint64_t>(data_ + pos) : load<std::uint32_t>(data_ + pos);
      pos += header_size_;
      return w;
    };
    const auto wrong_size = [&](std::uint64_t bytes) {
      fail(where_, fmt::format("{}: the data holds {} bytes, expected {}", label, bytes, expected));
    };
    std::vector<unsigned char> out;
    if (!compressed_) {
      const std::uint64_t bytes = word("size header");
      if (bytes != expected) wrong_size(bytes);
      need(bytes, "data");
      out.assign(data_ + pos, data_ + pos + bytes);
      end_ = std::max(end_, pos + bytes);
      return out;
    }
    const std::uint64_t nblocks = word("compression header");
    const std::uint64_t block = word("compression header");
    const std::uint64_t last = word("compression header");
    if (nblocks > 0 && (block == 0 || last > block))
      fail(where_, fmt::format("{}: bad compression header (block size {}, last block {})", label,
                               block, last));
    if (nblocks > (size_ - std::min(size_, pos)) / header_size_)
      fail(where_, fmt::format("{}: the compression header lists {} blocks, more than the file "
                               "holds (truncated?)",
                               label, nblocks));
    if (nblocks > 0) {
      const std::uint64_t last_size = last ? last : block;
      if (block > std::numeric_limits<std::uint64_t>::max() / nblocks)
        wrong_size(std::numeric_limits<std::uint64_t>::max());
      const std::uint64_t total = (nblocks - 1) * block + last_size;
      if (total != expected) wrong_size(total);
    } else if (expected != 0) {
      wrong_size(0);
    }
    std::vector<std::uint64_t> sizes(nblocks);
    for (auto& s : sizes) s = word("compression header");
    out.resize(expected);
    std::uint64_t written = 0;
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      need(sizes[b], "compressed data");
      const std::uint64_t want = (b + 1 == nblocks && last) ? last : block;
      uLongf got = static_cast<uLongf>(want);
      const int rc =
          uncompress(out.data() + written, &got, data_ + pos, static_cast<uLong>(sizes[b]));
      if (rc != Z_OK || got != want)
        fail(where_, fmt::format("{}: zlib block {} of {} is corrupt ({})", label, b + 1, nblocks,
                                 rc == Z_OK ? "wrong length" : zError(rc)));
      pos += sizes[b];
      written += want;
    }
    end_ = std::max(end_, pos);
    return out;
  }

  // The end of the furthest array decoded, from the start of the section.
  std::uint64_t end() const { return end_; }

 private:
  std::string where_;
  const unsigned char* data_;
  std::uint64_t size_;
  bool compressed_;
  std::size_t header_size_;
  std::uint64_t end_ = 0;
};

// One <DataArray> of the file, decoded.
struct RawArray {
  std::string name, type;
  int components = 1;
  std::vector<std::string> component_names;
  std::vector<unsigned char> bytes;
  std::size_t count() const { return bytes.size() / type_size(type); }
};

class ArrayReader {
 public:
  ArrayReader(std::string where, Appended& appended)
      : where_(std::move(where)), appended_(appended) {}

  // Decodes a DataArray of `tuples` tuples (components checked against `want_components`
  // when it is positive).
  RawArray read(const XmlElement& e, const std::string& context, std::uint64_t tuples,
                int want_components = 0) {
    if (e.name != "DataArray") fail(where_, fmt::format("unexpected <{}> in {}", e.name, context));
    RawArray a;
    a.name = e.attribute("Name") ? *e.attribute("Name") : std::string();
    const std::string label = fmt::format("{} array '{}'", context, a.name);
    a.type = required(where_, e, "type");
    const std::size_t tsize = type_size(a.type);
    if (tsize == 0) fail(where_, fmt::format("{}: unsupported type \"{}\"", label, a.type));
    if (const std::string* c = e.attribute("NumberOfComponents")) {
      const std::int64_t n = parse_count(where_, e, "NumberOfComponents", *c);
      if (n < 1 || n > 1024) fail(where_, fmt::format("{}: {} components", label, n));
      a.components = static_cast<int>(n);
    }
    for (int c = 0; c < a.components; ++c) {
      const std::string* cn = e.attribute(fmt::format("ComponentName{}", c));
      if (!cn) break;
      a.component_names.push_back(*cn);
    }
    if (a.component_names.size() != static_cast<std::size_t>(a.components))
      a.component_names.clear();
    if (want_components > 0 && a.components != want_components)
      fail(where_,
           fmt::format("{}: {} components, expected {}", label, a.components, want_components));
    const std::string& format = required(where_, e, "format");
    if (format != "appended")
      fail(where_,
           fmt::format("{}: format=\"{}\" is not supported (only appended)", label, format));
    const auto offset =
        static_cast<std::uint64_t>(parse_count(where_, e, "offset", required(where_, e, "offset")));
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() / 1024 / 8;
    if (tuples > limit) fail(where_, fmt::format("{}: too many tuples ({})", label, tuples));
    const std::uint64_t expected = tuples * static_cast<std::uint64_t>(a.components) * tsize;
    a.bytes = appended_.decode(label, offset, expected);
    return a;
  }

 private:
  std::string where_;
  Appended& appended_;
};

template <class Out>
std::vector<Out> convert(const std::string& where, const RawArray& a) {
  const std::size_t n = a.count();
  std::vector<Out> out(n);
  const unsigned char* p = a.bytes.data();
  const auto store = [&](auto value, std::size_t i) {
    using In = decltype(value);
    if constexpr (std::is_integral_v<Out> && std::is_integral_v<In>) {
      if (!std::in_range<Out>(value))
        fail(where, fmt::format("array '{}': value {} does not fit the reader's integer type",
                                a.name, value));
    }
    out[i] = static_cast<Out>(value);
  };
  const auto each = [&](auto tag) {
    using In = decltype(tag);
    for (std::size_t i = 0; i < n; ++i) store(load<In>(p + i * sizeof(In)), i);
  };
  const std::string& t = a.type;
  if constexpr (std::is_floating_point_v<Out>) {
    if (t == "Float64")
      each(double{});
    else if (t == "Float32")
      each(float{});
    else
      fail(where, fmt::format("array '{}': type {} where floats were expected", a.name, t));
  } else {
    if (t == "Int8")
      each(std::int8_t{});
    else if (t == "UInt8")
      each(std::uint8_t{});
    else if (t == "Int16")
      each(std::int16_t{});
    else if (t == "UInt16")
      each(std::uint16_t{});
    else if (t == "Int32")
      each(std::int32_t{});
    else if (t == "UInt32")
      each(std::uint32_t{});
    else if (t == "Int64")
      each(std::int64_t{});
    else if (t == "UInt64")
      each(std::uint64_t{});
    else
      fail(where, fmt::format("array '{}': type {} where integers were expected", a.name, t));
  }
  return out;
}

// Reads the arrays of <PointData>, <CellData> (tuples given) or <FieldData> (tuples < 0: each
// array's NumberOfTuples).
void read_attributes(const std::string& where, ArrayReader& reader, const XmlElement* parent,
                     const char* context, std::int64_t tuples,
                     std::map<std::string, VtuArray>& out) {
  if (!parent) return;
  for (const XmlElement& e : parent->children) {
    std::int64_t n = tuples;
    if (n < 0)
      n = parse_count(where, e, "NumberOfTuples", required(where, e, "NumberOfTuples"));
    RawArray raw = reader.read(e, context, static_cast<std::uint64_t>(n));
    if (raw.name.empty()) fail(where, fmt::format("a {} array has no Name", context));
    VtuArray a;
    a.name = raw.name;
    a.components = raw.components;
    a.component_names = raw.component_names;
    if (is_float(raw.type)) {
      a.type = VtuType::kFloat64;
      a.f64 = convert<double>(where, raw);
    } else {
      a.type = VtuType::kInt32;
      a.i32 = convert<std::int32_t>(where, raw);
    }
    if (!out.emplace(a.name, std::move(a)).second)
      fail(where, fmt::format("two {} arrays named '{}'", context, raw.name));
  }
}

}  // namespace

VtuData read_vtu(const std::string& path) {
  const std::string text = read_file(path);
  XmlParser parser(text, path);
  if (!parser.run("AppendedData")) fail(path, "no <AppendedData> section");
  const std::vector<XmlElement>& open = parser.open_elements();
  if (open.size() != 2 || open[0].name != "VTKFile")
    parser.error("<AppendedData> must be a child of the <VTKFile> root");
  const XmlElement& root = open[0];
  const XmlElement& appended_element = open[1];

  // The root and the encoding.
  if (required(path, root, "type") != "UnstructuredGrid")
    fail(path,
         fmt::format("VTKFile type=\"{}\", expected UnstructuredGrid", *root.attribute("type")));
  if (const std::string* order = root.attribute("byte_order"); order && *order != "LittleEndian")
    fail(path, fmt::format("byte_order=\"{}\" is not supported", *order));
  std::size_t header_size = 4;  // VTK's default header type is UInt32
  if (const std::string* h = root.attribute("header_type")) {
    if (*h == "UInt64")
      header_size = 8;
    else if (*h != "UInt32")
      fail(path, fmt::format("header_type=\"{}\" is not supported", *h));
  }
  const std::string* compressor = root.attribute("compressor");
  if (compressor && *compressor != "vtkZLibDataCompressor")
    fail(path, fmt::format("compressor=\"{}\" is not supported", *compressor));
  if (const std::string* enc = appended_element.attribute("encoding"); !enc || *enc != "raw")
    fail(path, "<AppendedData> must have encoding=\"raw\" (base64 is not supported)");

  // The binary section starts after the '_' marker.
  std::size_t pos = parser.position();
  while (pos < text.size() && std::strchr(" \t\r\n", text[pos]) && text[pos] != '\0') ++pos;
  if (pos >= text.size() || text[pos] != '_')
    fail(path, "no '_' marker at the start of the appended data (truncated?)");
  Appended appended(path, text, pos + 1, compressor != nullptr, header_size);
  ArrayReader reader(path, appended);

  const XmlElement& grid = only_child(path, root, "UnstructuredGrid");
  const XmlElement& piece = only_child(path, grid, "Piece");
  VtuData data;
  data.compressed = compressor != nullptr;
  data.num_points =
      parse_count(path, piece, "NumberOfPoints", required(path, piece, "NumberOfPoints"));
  data.num_cells =
      parse_count(path, piece, "NumberOfCells", required(path, piece, "NumberOfCells"));
  const auto npoints = static_cast<std::uint64_t>(data.num_points);
  const auto ncells = static_cast<std::uint64_t>(data.num_cells);

  read_attributes(path, reader, optional_child(path, grid, "FieldData"), "field", -1,
                  data.field_data);
  if (auto t = data.field_data.find("TimeValue");
      t != data.field_data.end() && t->second.f64.size() == 1)
    data.time = t->second.f64[0];
  read_attributes(path, reader, optional_child(path, piece, "PointData"), "point",
                  data.num_points, data.point_data);
  read_attributes(path, reader, optional_child(path, piece, "CellData"), "cell", data.num_cells,
                  data.cell_data);

  const XmlElement& points = only_child(path, piece, "Points");
  if (points.children.size() != 1) fail(path, "<Points> must hold exactly one DataArray");
  const std::vector<double> xyz =
      convert<double>(path, reader.read(points.children[0], "Points", npoints, 3));
  data.points.resize(npoints);
  for (std::size_t i = 0; i < npoints; ++i)
    data.points[i] = Vec3{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};

  const XmlElement& cells = only_child(path, piece, "Cells");
  const XmlElement* connectivity = nullptr;
  const XmlElement* offsets = nullptr;
  const XmlElement* types = nullptr;
  for (const XmlElement& e : cells.children) {
    const std::string* name = e.attribute("Name");
    const XmlElement** slot = !name                     ? nullptr
                              : *name == "connectivity" ? &connectivity
                              : *name == "offsets"      ? &offsets
                              : *name == "types"        ? &types
                                                        : nullptr;
    if (!slot) fail(path, "<Cells> holds an array other than connectivity, offsets and types");
    if (*slot) fail(path, fmt::format("two '{}' arrays in <Cells>", *name));
    *slot = &e;
  }
  if (!connectivity || !offsets || !types)
    fail(path, "<Cells> needs the connectivity, offsets and types arrays");
  data.offsets = convert<std::int64_t>(path, reader.read(*offsets, "Cells", ncells, 1));
  const std::vector<std::int64_t> type_values =
      convert<std::int64_t>(path, reader.read(*types, "Cells", ncells, 1));
  std::int64_t begin = 0;
  for (std::size_t c = 0; c < ncells; ++c) {
    if (data.offsets[c] < begin)
      fail(path,
           fmt::format("cell {}: end offset {} is before its start {}", c, data.offsets[c], begin));
    begin = data.offsets[c];
    if (type_values[c] < 0 || type_values[c] > 255)
      fail(path, fmt::format("cell {}: type {} is not a VTK cell type", c, type_values[c]));
  }
  data.types.assign(type_values.begin(), type_values.end());
  data.connectivity = convert<std::int64_t>(
      path, reader.read(*connectivity, "Cells", static_cast<std::uint64_t>(begin), 1));
  for (std::size_t i = 0; i < data.connectivity.size(); ++i)
    if (data.connectivity[i] < 0 || data.connectivity[i] >= data.num_points)
      fail(path, fmt::format("connectivity[{}] = {} is not a point id (there are {} points)", i,
                             data.connectivity[i], data.num_points));

  // After the furthest array: the closing tags and nothing else.
  parser.seek(pos + 1 + appended.end());
  parser.run();

  // The writer's empty-grid placeholder (vtu.hpp): no point, one polygon of no nodes.
  if (data.num_points == 0 && data.num_cells == 1 && data.types[0] == 7 && data.offsets[0] == 0) {
    data.num_cells = 0;
    data.offsets.clear();
    data.types.clear();
    for (auto& [name, a] : data.cell_data) {
      a.f64.clear();
      a.i32.clear();
    }
  }
  return data;
}

std::vector<std::pair<double, std::string>> read_pvd(const std::string& path) {
  const std::string text = read_file(path);
  XmlParser parser(text, path);
  parser.run();
  const XmlElement& root = parser.root();
  if (root.name != "VTKFile")
    fail(path, fmt::format("root element <{}>, expected <VTKFile>", root.name));
  if (required(path, root, "type") != "Collection")
    fail(path, fmt::format("VTKFile type=\"{}\", expected Collection", *root.attribute("type")));
  const XmlElement& collection = only_child(path, root, "Collection");
  std::vector<std::pair<double, std::string>> steps;
  for (const XmlElement& e : collection.children) {
    if (e.name != "DataSet") fail(path, fmt::format("unexpected <{}> in <Collection>", e.name));
    const std::string& t = required(path, e, "timestep");
    double time = 0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), time);
    if (ec != std::errc() || ptr != t.data() + t.size() || t.empty())
      fail(path, fmt::format("timestep=\"{}\" is not a number", t));
    const std::string& file = required(path, e, "file");
    if (file.empty()) fail(path, "a DataSet with an empty file attribute");
    steps.emplace_back(time, file);
  }
  return steps;
}

}  // namespace cdem
