// The MSH reader (msh_reader.hpp). Layouts from the MSH format chapter of the Gmsh manual, checked
// against files written by libgmsh 4.8 (2.2 and 4.1, ASCII and binary; 4.0 ASCII) and against
// Gmsh 4.x's reader for 4.0 binary, which Gmsh 4.8 no longer writes:
//   2.2  $Nodes: n, then per node: tag x y z (binary: int32 tag, 3 doubles).
//        $Elements: n, then per element: tag type ntags tag... node... (binary: blocks of int32
//        header type, count, ntags, then per element int32 tag, tags, nodes).
//   4.0  $Entities: 4 counts (binary: unsigned long), per entity: int tag, 6 doubles (points
//        too), numPhysicals + int tags, and for curves and up numBounding + int tags.
//        $Nodes: numBlocks numNodes; block: entityTag entityDim parametric count; per node tag
//        x y z [u [v]] (binary: int32 tag). $Elements: numBlocks numElements; block:
//        entityTag entityDim type count; per element tag node... (binary: int32).
//   4.1  $Entities: as 4.0 but points have x y z only, counts size_t. $Nodes: numBlocks numNodes
//        minTag maxTag; block: entityDim entityTag parametric count; the block's tags, then its
//        coordinates x y z [u [v [w]]] (binary: size_t tags). $Elements: numBlocks numElements
//        minTag maxTag; block: entityDim entityTag type count; per element tag node...
//        (binary: size_t).
// Counts are checked against the bytes left before anything is reserved: every item needs at
// least a known number of bytes (binary: its exact size; ASCII: two per number, a digit and a
// separator), so memory stays proportional to the file's size whatever the counts say.
#include "cdem/mesh/msh_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <utility>

#include "cdem/core/error.hpp"
#include "cdem/core/text.hpp"
#include "cdem/mesh/msh_element_types.hpp"

namespace cdem {
namespace {

enum class Version { V22, V40, V41 };

// Positions of nodes and elements for messages, without keeping the file: bit 63 set for a
// byte offset (binary data), else a line number; bits 56-62 the section (1 $Nodes, 2 $Elements).
constexpr std::uint64_t kBinaryBit = std::uint64_t{1} << 63;
constexpr int kSectionShift = 56;
constexpr std::uint64_t kValueMask = (std::uint64_t{1} << kSectionShift) - 1;
enum Section : std::uint64_t { kNodes = 1, kElements = 2 };

std::string locate_position(std::uint64_t pos) {
  const std::uint64_t section = (pos & ~kBinaryBit) >> kSectionShift;
  const char* name = section == kNodes ? "$Nodes" : section == kElements ? "$Elements" : "file";
  if (pos & kBinaryBit) return fmt::format("{}, byte {}", name, pos & kValueMask);
  return fmt::format("{}, line {}", name, pos & kValueMask);
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// An element of an MSH 2.2 file, before duplicate lines are merged (Gmsh writes an element once
// per physical group it belongs to, with the same tag).
struct V2Element {
  std::uint64_t tag = 0;
  int type = 0;
  int physical = 0;    // 0: none
  int elementary = 0;  // the elementary entity
  std::size_t first_node = 0;
  std::uint64_t position = 0;
};

class Parser {
 public:
  Parser(std::string_view buf, const std::string& source) : buf_(buf), source_(source) {}

  RawModel run() {
    mesh_format();
    while (true) {
      skip_space();
      if (pos_ >= buf_.size()) break;
      if (buf_[pos_] != '$') {
        // Gmsh skips lines outside sections; so does this reader.
        skip_line();
        continue;
      }
      const std::size_t start = pos_;
      const std::string name = section_header();
      section_ = name;
      data_mode();
      if (name == "$MeshFormat") {
        fail_at(start, false, "a second $MeshFormat section");
      } else if (name == "$PhysicalNames") {
        once(seen_names_, start);
        physical_names();
      } else if (name == "$Entities" && version_ != Version::V22) {
        once(seen_entities_, start);
        entities();
      } else if (name == "$PartitionedEntities") {
        fail_at(start, false,
                "partitioned meshes are not supported (save the mesh without partitions)");
      } else if (name == "$Nodes") {
        once(seen_nodes_, start);
        if (version_ == Version::V22)
          nodes_v2();
        else
          nodes_v4();
      } else if (name == "$Elements") {
        once(seen_elements_, start);
        if (version_ == Version::V22)
          elements_v2();
        else
          elements_v4();
      } else {
        skip_section(name, start);
      }
      section_.clear();
    }
    if (!seen_nodes_) fail_file("no $Nodes section");
    if (!seen_elements_) fail_file("no $Elements section");
    return finish();
  }

 private:
  std::string_view buf_;
  const std::string& source_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;  // line of pos_
  Version version_ = Version::V41;
  bool binary_ = false;
  std::string section_;
  bool seen_names_ = false, seen_entities_ = false, seen_nodes_ = false, seen_elements_ = false;
  RawModel raw_;
  std::map<std::pair<int, int>, std::vector<int>> entities_;  // (dim, tag) -> physical tags
  std::map<std::pair<int, int>, std::string> names_;          // (dim, physical tag) -> name
  std::vector<RawElementBlock> blocks_v4_;
  std::vector<V2Element> v2_elems_;
  std::vector<std::uint64_t> v2_nodes_;
  bool binary_file_ = false;

  // Section data is binary in a binary file; markers, counts of 2.2 and names are text.
  void text_mode() { binary_ = false; }
  void data_mode() { binary_ = binary_file_; }
  // The $End marker of a section (text), then back to the file's data mode.
  void end_section(const std::string& name) {
    text_mode();
    expect_end(name);
    data_mode();
  }

  // ---- messages ----
  [[noreturn]] void fail_file(const std::string& what) const {
    throw MeshError(fmt::format("{}: {}", source_, what));
  }
  // `binary`: the offset is in binary data (reported as a byte), else as a line.
  [[noreturn]] void fail_at(std::size_t offset, bool binary, const std::string& what) const {
    const std::string where = binary ? fmt::format("byte {}", offset)
                                     : fmt::format("line {}", line_column(buf_, offset).line);
    if (section_.empty()) throw MeshError(fmt::format("{}: {}: {}", source_, where, what));
    throw MeshError(fmt::format("{}: {}, {}: {}", source_, printable(section_), where, what));
  }
  [[noreturn]] void fail_here(const std::string& what) const { fail_at(pos_, binary_, what); }
  void once(bool& seen, std::size_t start) {
    if (seen) fail_at(start, false, fmt::format("a second {} section", printable(section_)));
    seen = true;
  }
  // Where the next node or element starts (in text, after the whitespace before it).
  std::uint64_t position(Section s) {
    if (binary_) return kBinaryBit | (std::uint64_t{s} << kSectionShift) | pos_;
    skip_space();
    return (std::uint64_t{s} << kSectionShift) | line_;
  }

  // ---- text ----
  void skip_space() {
    while (pos_ < buf_.size() && is_space(buf_[pos_])) {
      if (buf_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  void skip_line() {
    while (pos_ < buf_.size() && buf_[pos_] != '\n') ++pos_;
    if (pos_ < buf_.size()) {
      ++pos_;
      ++line_;
    }
  }
  // The rest of the current line (without its line feed), and moves past it.
  std::string_view rest_of_line() {
    const std::size_t start = pos_;
    while (pos_ < buf_.size() && buf_[pos_] != '\n') ++pos_;
    std::string_view s = buf_.substr(start, pos_ - start);
    if (pos_ < buf_.size()) {
      ++pos_;
      ++line_;
    }
    while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
    return s;
  }
  std::string section_header() {
    std::string_view s = rest_of_line();
    if (s.size() > 64) s = s.substr(0, 64);
    return std::string(s);
  }
  // A number without a leading '+' (which C's scanf, hence Gmsh, accepts and from_chars not).
  static std::string_view unsigned_part(std::string_view t) {
    if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
    return t;
  }
  // The next whitespace-separated token; `what` says what was expected (for messages).
  std::string_view token(const char* what) {
    skip_space();
    if (pos_ >= buf_.size()) fail_here(fmt::format("the file ends where {} was expected", what));
    const std::size_t start = pos_;
    while (pos_ < buf_.size() && !is_space(buf_[pos_])) ++pos_;
    return buf_.substr(start, pos_ - start);
  }
  template <class T>
  T integer_token(const char* what) {
    const std::size_t before = pos_;
    const std::string_view t = token(what);
    const std::string_view digits = unsigned_part(t);
    T v{};
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ec != std::errc() || end != digits.data() + digits.size()) {
      pos_ = before;
      skip_space();
      fail_here(fmt::format("expected {} ({}), found '{}'", what,
                            std::is_signed_v<T> ? "an integer" : "a whole number", printable(t)));
    }
    return v;
  }
  double double_token(const char* what) {
    const std::size_t before = pos_;
    const std::string_view t = token(what);
    const std::string_view digits = unsigned_part(t);
    double v = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ec != std::errc() || end != digits.data() + digits.size()) {
      pos_ = before;
      skip_space();
      fail_here(fmt::format("expected {} (a number), found '{}'", what, printable(t)));
    }
    return v;
  }
  void expect_end(const std::string& name) {
    const std::string end = "$End" + name.substr(1);
    skip_space();
    const std::size_t start = pos_;
    std::string_view t;
    if (pos_ < buf_.size()) {
      while (pos_ < buf_.size() && !is_space(buf_[pos_])) ++pos_;
      t = buf_.substr(start, pos_ - start);
    }
    if (t != end) {
      pos_ = start;
      fail_at(start, false,
              t.empty() ? fmt::format("the file ends before {}", end)
                        : fmt::format("expected {}, found '{}' (more data than the section's "
                                      "counts say, or a count too small)",
                                      end, printable(t)));
    }
    skip_line();
  }
  void skip_section(const std::string& name, std::size_t start) {
    if (name.size() < 2 || name.find_first_of(" \t") != std::string::npos)
      fail_at(start, false, fmt::format("'{}' is not a section header", printable(name)));
    const std::string end = "\n$End" + name.substr(1);
    const std::size_t at = buf_.find(end, pos_);
    if (at == std::string_view::npos)
      fail_at(start, false,
              fmt::format("section {} has no $End{}", printable(name), printable(name.substr(1))));
    line_ += static_cast<std::size_t>(std::count(buf_.begin() + static_cast<long>(pos_),
                                                 buf_.begin() + static_cast<long>(at + 1), '\n'));
    pos_ = at + 1;
    skip_line();
  }

  // ---- binary ----
  template <class T>
  T bin(const char* what) {
    if (buf_.size() - pos_ < sizeof(T))
      fail_here(fmt::format("the file ends inside {} ({} bytes needed, {} left)", what, sizeof(T),
                            buf_.size() - pos_));
    T v;
    std::memcpy(&v, buf_.data() + pos_, sizeof(T));
    line_ += static_cast<std::size_t>(std::count(buf_.begin() + static_cast<long>(pos_),
                                                 buf_.begin() + static_cast<long>(pos_ + sizeof(T)),
                                                 '\n'));
    pos_ += sizeof(T);
    return v;
  }

  // ---- numbers of either kind ----
  // A count, size or tag stored as size_t (4.1 binary), unsigned long (4.0 binary) or text.
  std::uint64_t u64(const char* what) {
    return binary_ ? bin<std::uint64_t>(what) : integer_token<std::uint64_t>(what);
  }
  // An int (tags, dimensions, types); text must fit an int too.
  int i32(const char* what) {
    if (binary_) return bin<std::int32_t>(what);
    const std::size_t before = pos_;
    const auto v = integer_token<std::int64_t>(what);
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
      pos_ = before;
      skip_space();
      fail_here(fmt::format("{} {} is out of range", what, v));
    }
    return static_cast<int>(v);
  }
  double f64(const char* what) { return binary_ ? bin<double>(what) : double_token(what); }
  // An entity block's head: MSH 4.1 writes its dimension then its tag, 4.0 the tag first.
  std::pair<int, int> entity_block_head() {
    if (version_ == Version::V41) {
      const int dim = i32("an entity dimension");
      return {dim, i32("an entity tag")};
    }
    const int etag = i32("an entity tag");
    return {i32("an entity dimension"), etag};
  }
  // MSH 4.1's smallest and largest tag of a section (not needed: tags are checked one by one).
  void skip_tag_range(const char* smallest, const char* largest) {
    if (version_ != Version::V41) return;
    (void)u64(smallest);
    (void)u64(largest);
  }
  // A node or element tag: size_t in 4.1, int elsewhere; >= 1 and within int64.
  std::uint64_t tag(const char* what) {
    const std::size_t before = pos_;
    std::uint64_t t;
    if (version_ == Version::V41 || !binary_) {
      t = binary_ ? bin<std::uint64_t>(what) : integer_token<std::uint64_t>(what);
    } else {
      const std::int32_t v = bin<std::int32_t>(what);
      if (v < 1) fail_at(before, true, fmt::format("{} {} (tags start at 1)", what, v));
      t = static_cast<std::uint64_t>(v);
    }
    if (t < 1 || t > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      fail_at(before, binary_, fmt::format("{} {} is out of range (tags start at 1)", what, t));
    return t;
  }
  // A count of items each needing at least `min_bytes` in the file: refused when the rest of
  // the file could not hold them, before anything is allocated.
  void check_count(std::uint64_t count, std::uint64_t min_bytes, const char* what,
                   std::size_t at) const {
    const std::uint64_t left = buf_.size() - pos_;
    if (min_bytes > 0 && count > left / min_bytes)
      fail_at(at, binary_,
              fmt::format("{} {}: more than the rest of the file ({} bytes) can hold", what, count,
                          left));
  }
  // Bytes of an int-or-size number in this file: 2 in text (a digit and a separator).
  std::uint64_t tag_bytes() const { return binary_ ? (version_ == Version::V41 ? 8 : 4) : 2; }
  std::uint64_t count_bytes() const { return binary_ ? 8 : 2; }
  std::uint64_t int_bytes() const { return binary_ ? 4 : 2; }
  std::uint64_t double_bytes() const { return binary_ ? 8 : 2; }

  // ---- sections ----
  void mesh_format() {
    skip_space();
    const std::size_t start = pos_;
    const std::string head = section_header();
    if (head != "$MeshFormat") {
      if (head == "$NOD" || head == "$NOE")
        fail_at(start, false, "MSH version 1 is not supported (2.2, 4.0 and 4.1 are)");
      fail_at(start, false,
              "not a Gmsh MSH file (it must start with $MeshFormat; cdemblast reads MSH 2.2, 4.0 "
              "and 4.1 meshes only, never scripts)");
    }
    section_ = head;
    const std::size_t at = pos_;
    const std::string_view line = rest_of_line();
    std::vector<std::string_view> words;
    for (std::size_t i = 0; i < line.size();) {
      while (i < line.size() && is_space(line[i])) ++i;
      const std::size_t b = i;
      while (i < line.size() && !is_space(line[i])) ++i;
      if (i > b) words.push_back(line.substr(b, i - b));
    }
    if (words.size() != 3)
      fail_at(at, false,
              fmt::format("expected 'version file-type data-size', found '{}'", printable(line)));
    if (words[0] == "2.2")
      version_ = Version::V22;
    else if (words[0] == "4" || words[0] == "4.0")
      version_ = Version::V40;
    else if (words[0] == "4.1")
      version_ = Version::V41;
    else
      fail_at(at, false,
              fmt::format("MSH version '{}' is not supported (2.2, 4.0 and 4.1 are)",
                          printable(words[0])));
    if (words[1] != "0" && words[1] != "1")
      fail_at(at, false,
              fmt::format("file-type '{}': expected 0 (ASCII) or 1 (binary)", printable(words[1])));
    if (words[2] != "8")
      fail_at(at, false,
              fmt::format("data-size '{}': only 8 (double precision) is supported",
                          printable(words[2])));
    binary_file_ = words[1] == "1";
    if (binary_file_) {
      data_mode();
      const std::int32_t one = bin<std::int32_t>("the binary check integer");
      if (one == 0x01000000)
        fail_at(pos_ - 4, true, "a big-endian binary file (only little-endian is supported)");
      if (one != 1)
        fail_at(pos_ - 4, true, fmt::format("the binary check integer is {}, not 1", one));
    }
    end_section("$MeshFormat");
  }

  void physical_names() {
    text_mode();  // text in binary files too
    const std::size_t at = pos_;
    const auto n = integer_token<std::uint64_t>("the number of physical names");
    check_count(n, 6, "number of physical names", at);
    for (std::uint64_t i = 0; i < n; ++i) {
      const int dim = i32("a physical dimension");
      if (dim < 0 || dim > 3)
        fail_here(fmt::format("physical dimension {} (expected 0 to 3)", dim));
      const int ptag = i32("a physical tag");
      while (pos_ < buf_.size() && (buf_[pos_] == ' ' || buf_[pos_] == '\t')) ++pos_;
      if (pos_ >= buf_.size() || buf_[pos_] != '"')
        fail_here(fmt::format("physical group {} of dimension {}: expected a name in double quotes",
                              ptag, dim));
      const std::size_t b = ++pos_;
      while (pos_ < buf_.size() && buf_[pos_] != '"' && buf_[pos_] != '\n') ++pos_;
      if (pos_ >= buf_.size() || buf_[pos_] != '"')
        fail_here(fmt::format("physical group {} of dimension {}: the name has no closing quote",
                              ptag, dim));
      const std::string_view name = buf_.substr(b, pos_ - b);
      if (name.size() > 1024)
        fail_here(
            fmt::format("physical group {}: a name of {} bytes (at most 1024)", ptag, name.size()));
      if (const auto bad = check_text(name, false))
        fail_at(b + bad->offset, false,
                fmt::format("physical group {} of dimension {}: its name holds {}", ptag, dim,
                            bad->what));
      names_[{dim, ptag}] = std::string(name);
      skip_line();  // Gmsh ignores the rest of the line
    }
    end_section("$PhysicalNames");
  }

  void entities() {
    const std::size_t at = pos_;
    std::uint64_t n[4];
    for (auto& c : n) c = u64("an entity count");
    // Bytes of the smallest entity of each dimension.
    const std::uint64_t point = version_ == Version::V41 ? 4 * int_bytes() + count_bytes()
                                                         : 7 * double_bytes() + count_bytes();
    const std::uint64_t other = int_bytes() + 6 * double_bytes() + 2 * count_bytes();
    for (int d = 0; d < 4; ++d) check_count(n[d], d == 0 ? point : other, "entity count", at);
    for (int d = 0; d < 4; ++d)
      for (std::uint64_t i = 0; i < n[d]; ++i) {
        const std::size_t start = pos_;
        const int etag = i32("an entity tag");
        const int nbox = d == 0 && version_ == Version::V41 ? 3 : 6;
        for (int k = 0; k < nbox; ++k) (void)f64("a bounding box coordinate");
        const std::size_t at_phys = pos_;
        const std::uint64_t np = u64("the number of physical tags");
        check_count(np, int_bytes(), "number of physical tags", at_phys);
        std::vector<int> phys;
        phys.reserve(np);
        for (std::uint64_t k = 0; k < np; ++k) phys.push_back(i32("a physical tag"));
        if (d > 0) {
          const std::size_t at_bound = pos_;
          const std::uint64_t nb = u64("the number of bounding entities");
          check_count(nb, int_bytes(), "number of bounding entities", at_bound);
          for (std::uint64_t k = 0; k < nb; ++k) (void)i32("a bounding entity tag");
        }
        if (!entities_.emplace(std::make_pair(d, etag), std::move(phys)).second)
          fail_at(start, binary_,
                  fmt::format("entity {} of dimension {} is listed twice", etag, d));
      }
    end_section("$Entities");
  }

  void add_node(std::uint64_t t, const double* xyz, std::uint64_t pos, std::size_t at) {
    static const char* axis[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(xyz[k]))
        fail_at(
            at, binary_,
            fmt::format("node {}: coordinate {} = {} is not a finite number", t, axis[k], xyz[k]));
      if (std::abs(xyz[k]) > kMaxNodeCoordinate)
        fail_at(at, binary_,
                fmt::format("node {}: coordinate {} = {:g} is beyond +-{:g} (a corrupt file, or a "
                            "mesh in a unit far smaller than metres)",
                            t, axis[k], xyz[k], kMaxNodeCoordinate));
    }
    raw_.node_tags.push_back(t);
    raw_.node_coords.push_back(Vec3{xyz[0], xyz[1], xyz[2]});
    raw_.node_offsets.push_back(pos);
  }

  void reserve_nodes(std::uint64_t n) {
    raw_.node_tags.reserve(n);
    raw_.node_coords.reserve(n);
    raw_.node_offsets.reserve(n);
  }

  void nodes_v2() {
    const std::size_t at = pos_;
    text_mode();  // the count is text in binary files too
    const std::uint64_t n = integer_token<std::uint64_t>("the number of nodes");
    data_mode();
    if (binary_) skip_line_end();
    check_count(n, binary_ ? 4 + 24 : 8, "number of nodes", at);
    reserve_nodes(n);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t pos = position(kNodes);
      const std::size_t start = pos_;
      const std::uint64_t t = tag("a node tag");
      double xyz[3];
      for (double& c : xyz) c = f64("a node coordinate");
      add_node(t, xyz, pos, start);
    }
    end_section("$Nodes");
  }

  void nodes_v4() {
    const std::size_t at = pos_;
    const std::uint64_t nblocks = u64("the number of node blocks");
    const std::uint64_t n = u64("the number of nodes");
    skip_tag_range("the smallest node tag", "the largest node tag");
    const std::uint64_t per_node = binary_ ? tag_bytes() + 24 : 8;
    check_count(nblocks, 3 * int_bytes() + count_bytes(), "number of node blocks", at);
    check_count(n, per_node, "number of nodes", at);
    reserve_nodes(n);
    std::uint64_t total = 0;
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      const std::size_t start = pos_;
      const auto [dim, etag] = entity_block_head();
      (void)etag;
      if (dim < 0 || dim > 3)
        fail_at(start, binary_,
                fmt::format("node block {}: entity dimension {} (expected 0 to 3)", b + 1, dim));
      const int parametric = i32("the parametric flag");
      if (parametric != 0 && parametric != 1)
        fail_at(
            start, binary_,
            fmt::format("node block {}: parametric flag {} (expected 0 or 1)", b + 1, parametric));
      const std::size_t at_count = pos_;
      const std::uint64_t count = u64("the number of nodes in the block");
      if (count > n - total)
        fail_at(at_count, binary_,
                fmt::format("node block {} holds {} nodes, more than the {} the header has left",
                            b + 1, count, n - total));
      check_count(count, per_node, "number of nodes in the block", at_count);
      // Parametric coordinates: u (curves), u v (surfaces); 4.1 also w in volumes.
      const int nparam = parametric ? (version_ == Version::V41 ? dim : (dim == 3 ? 0 : dim)) : 0;
      if (version_ == Version::V41) {
        // The block's tags, then its coordinates.
        std::vector<std::uint64_t> tags, positions;
        tags.reserve(count);
        positions.reserve(count);
        for (std::uint64_t i = 0; i < count; ++i) {
          positions.push_back(position(kNodes));
          tags.push_back(tag("a node tag"));
        }
        for (std::uint64_t i = 0; i < count; ++i) {
          if (!binary_) skip_space();
          const std::size_t cstart = pos_;
          double xyz[3];
          for (double& c : xyz) c = f64("a node coordinate");
          for (int k = 0; k < nparam; ++k) (void)f64("a parametric coordinate");
          add_node(tags[i], xyz, positions[i], cstart);
        }
      } else {
        for (std::uint64_t i = 0; i < count; ++i) {
          const std::uint64_t pos = position(kNodes);
          const std::size_t start_node = pos_;
          const std::uint64_t t = tag("a node tag");
          double xyz[3];
          for (double& c : xyz) c = f64("a node coordinate");
          for (int k = 0; k < nparam; ++k) (void)f64("a parametric coordinate");
          add_node(t, xyz, pos, start_node);
        }
      }
      total += count;
    }
    if (total != n)
      fail_here(fmt::format("the node blocks hold {} nodes, the header says {}", total, n));
    end_section("$Nodes");
  }

  // Text header lines of binary sections end with a line feed before the binary data.
  void skip_line_end() {
    while (pos_ < buf_.size() && (buf_[pos_] == ' ' || buf_[pos_] == '\t' || buf_[pos_] == '\r'))
      ++pos_;
    if (pos_ < buf_.size() && buf_[pos_] == '\n') {
      ++pos_;
      ++line_;
    }
  }

  const MshElementType& element_type(int type, int entity_dim, std::size_t at) const {
    const MshElementType* t = msh_element_type(type);
    if (!t) fail_at(at, binary_, fmt::format("unknown element type {}", type));
    if (t->nodes <= 0)
      fail_at(at, binary_,
              fmt::format("element type '{}' (Gmsh type {}) has a variable number of nodes; not "
                          "supported",
                          t->name, type));
    if (entity_dim >= 0 && t->dim != entity_dim)
      fail_at(at, binary_,
              fmt::format("'{}' elements (dimension {}) on an entity of dimension {}", t->name,
                          t->dim, entity_dim));
    return *t;
  }

  void elements_v4() {
    const std::size_t at = pos_;
    const std::uint64_t nblocks = u64("the number of element blocks");
    const std::uint64_t n = u64("the number of elements");
    skip_tag_range("the smallest element tag", "the largest element tag");
    check_count(nblocks, 3 * int_bytes() + count_bytes(), "number of element blocks", at);
    check_count(n, 2 * tag_bytes(), "number of elements", at);
    std::uint64_t total = 0;
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      const std::size_t start = pos_;
      const auto [dim, etag] = entity_block_head();
      if (dim < 0 || dim > 3)
        fail_at(start, binary_,
                fmt::format("element block {}: entity dimension {} (expected 0 to 3)", b + 1, dim));
      const int type = i32("an element type");
      const MshElementType& et = element_type(type, dim, start);
      const std::size_t at_count = pos_;
      const std::uint64_t count = u64("the number of elements in the block");
      if (count > n - total)
        fail_at(at_count, binary_,
                fmt::format("element block {} holds {} elements, more than the {} the header has "
                            "left",
                            b + 1, count, n - total));
      const auto nn = static_cast<std::uint64_t>(et.nodes);
      check_count(count, (1 + nn) * tag_bytes(), "number of elements in the block", at_count);
      RawElementBlock blk;
      blk.entity_dim = dim;
      blk.entity_tag = etag;
      blk.type = type;
      blk.tags.reserve(count);
      blk.nodes.reserve(count * nn);
      blk.offsets.reserve(count);
      for (std::uint64_t i = 0; i < count; ++i) {
        blk.offsets.push_back(position(kElements));
        blk.tags.push_back(tag("an element tag"));
        for (std::uint64_t k = 0; k < nn; ++k) blk.nodes.push_back(tag("a node tag"));
      }
      total += count;
      blocks_v4_.push_back(std::move(blk));
    }
    if (total != n)
      fail_here(fmt::format("the element blocks hold {} elements, the header says {}", total, n));
    end_section("$Elements");
  }

  void elements_v2() {
    const std::size_t at = pos_;
    text_mode();  // the count is text in binary files too
    const std::uint64_t n = integer_token<std::uint64_t>("the number of elements");
    data_mode();
    if (binary_) skip_line_end();
    // The smallest element: tag, type, number of tags and one node (4 numbers).
    check_count(n, 4 * int_bytes(), "number of elements", at);
    v2_elems_.reserve(n);
    if (!binary_) {
      for (std::uint64_t i = 0; i < n; ++i) {
        V2Element e;
        e.position = position(kElements);
        e.tag = tag("an element tag");
        const std::size_t at_type = pos_;
        e.type = i32("an element type");
        const MshElementType& t = element_type(e.type, -1, at_type);
        const std::size_t at_tags = pos_;
        const int ntags = i32("the number of tags");
        if (ntags < 0) fail_at(at_tags, false, fmt::format("element {}: {} tags", e.tag, ntags));
        check_count(static_cast<std::uint64_t>(ntags), 2, "number of tags", at_tags);
        read_v2_tags(e, ntags);
        read_v2_nodes(e, t);
        v2_elems_.push_back(e);
      }
    } else {
      std::uint64_t total = 0;
      while (total < n) {
        const std::size_t start = pos_;
        const int type = i32("an element type");
        const MshElementType& t = element_type(type, -1, start);
        const int follow = i32("the number of elements that follow");
        const int ntags = i32("the number of tags");
        if (follow < 1 || static_cast<std::uint64_t>(follow) > n - total)
          fail_at(start, true,
                  fmt::format("an element header announces {} elements, {} are left", follow,
                              n - total));
        if (ntags < 0) fail_at(start, true, fmt::format("{} tags per element", ntags));
        check_count(
            static_cast<std::uint64_t>(follow),
            4 * (1 + static_cast<std::uint64_t>(ntags) + static_cast<std::uint64_t>(t.nodes)),
            "number of elements", start);
        for (int i = 0; i < follow; ++i) {
          V2Element e;
          e.position = position(kElements);
          e.tag = tag("an element tag");
          e.type = type;
          read_v2_tags(e, ntags);
          read_v2_nodes(e, t);
          v2_elems_.push_back(e);
        }
        total += static_cast<std::uint64_t>(follow);
      }
    }
    end_section("$Elements");
  }
  void read_v2_tags(V2Element& e, int ntags) {
    for (int k = 0; k < ntags; ++k) {
      const int t = i32("an element tag (physical, elementary, partitions)");
      if (k == 0) e.physical = t;
      if (k == 1) e.elementary = t;
    }
  }
  void read_v2_nodes(V2Element& e, const MshElementType& t) {
    e.first_node = v2_nodes_.size();
    for (int k = 0; k < t.nodes; ++k) v2_nodes_.push_back(tag("a node tag"));
  }

  // ---- the model ----
  RawModel finish() {
    raw_.locate = locate_position;
    if (version_ == Version::V22)
      finish_v2();
    else
      finish_v4();
    return std::move(raw_);
  }

  // Blocks ordered by (entity dim, entity tag, type), blocks of one key merged in file order
  // (Gmsh keeps an entity's elements of one type together).
  static void order_blocks(std::vector<RawElementBlock>& blocks) {
    std::stable_sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) {
      return std::tie(a.entity_dim, a.entity_tag, a.type) <
             std::tie(b.entity_dim, b.entity_tag, b.type);
    });
    std::vector<RawElementBlock> merged;
    for (auto& b : blocks) {
      if (!merged.empty() && merged.back().entity_dim == b.entity_dim &&
          merged.back().entity_tag == b.entity_tag && merged.back().type == b.type) {
        auto& m = merged.back();
        m.tags.insert(m.tags.end(), b.tags.begin(), b.tags.end());
        m.nodes.insert(m.nodes.end(), b.nodes.begin(), b.nodes.end());
        m.offsets.insert(m.offsets.end(), b.offsets.begin(), b.offsets.end());
      } else {
        merged.push_back(std::move(b));
      }
    }
    blocks.swap(merged);
  }

  std::vector<RawPhysicalGroup> groups_of(
      const std::map<std::pair<int, int>, std::vector<int>>& entity_physicals) const {
    std::map<std::pair<int, int>, RawPhysicalGroup> groups;
    for (const auto& [key, phys] : entity_physicals)
      for (int p : phys) {
        auto& g = groups[{key.first, p}];
        g.dim = key.first;
        g.tag = p;
        if (std::find(g.entities.begin(), g.entities.end(), key.second) == g.entities.end())
          g.entities.push_back(key.second);
      }
    std::vector<RawPhysicalGroup> out;
    for (auto& [key, g] : groups) {
      if (auto it = names_.find(key); it != names_.end()) g.name = it->second;
      out.push_back(std::move(g));
    }
    return out;
  }

  void finish_v4() {
    order_blocks(blocks_v4_);
    raw_.blocks = std::move(blocks_v4_);
    raw_.groups = groups_of(entities_);
  }

  // MSH 2.2: physical groups are per element. An element written once per physical group (the
  // same tag, type and nodes) is one element in several groups; the same tag with other nodes
  // is an error. Elements are then put on synthetic entities, one per (dimension, elementary
  // entity, set of physical groups), so that the entity rules of assemble_mesh apply.
  void finish_v2() {
    const std::size_t n = v2_elems_.size();
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return v2_elems_[a].tag < v2_elems_[b].tag;
    });
    std::vector<std::vector<int>> phys(n);
    std::vector<char> merged(n, 0);
    for (std::size_t i = 0; i < n;) {
      std::size_t j = i + 1;
      const V2Element& first = v2_elems_[order[i]];
      if (first.physical != 0) phys[order[i]].push_back(first.physical);
      while (j < n && v2_elems_[order[j]].tag == first.tag) {
        const V2Element& again = v2_elems_[order[j]];
        const MshElementType* t = msh_element_type(first.type);
        const bool same =
            again.type == first.type &&
            std::equal(v2_nodes_.begin() + static_cast<long>(first.first_node),
                       v2_nodes_.begin() + static_cast<long>(first.first_node + t->nodes),
                       v2_nodes_.begin() + static_cast<long>(again.first_node));
        if (!same)
          fail_file(fmt::format(
              "element tag {} is used twice ({} and {}) for different elements "
              "(element tags must be unique)",
              first.tag, locate_position(first.position), locate_position(again.position)));
        if (again.physical != 0) phys[order[i]].push_back(again.physical);
        merged[order[j]] = 1;
        ++j;
      }
      std::sort(phys[order[i]].begin(), phys[order[i]].end());
      phys[order[i]].erase(std::unique(phys[order[i]].begin(), phys[order[i]].end()),
                           phys[order[i]].end());
      i = j;
    }
    // Synthetic entities and their physical groups.
    using Key = std::tuple<int, int, std::vector<int>>;  // dim, elementary, physicals
    std::map<Key, int> entity_of;
    for (std::size_t i = 0; i < n; ++i)
      if (!merged[i]) {
        const V2Element& e = v2_elems_[i];
        entity_of.emplace(Key{msh_element_type(e.type)->dim, e.elementary, phys[i]}, 0);
      }
    int next = 0;
    std::map<std::pair<int, int>, std::vector<int>> entity_physicals;
    for (auto& [key, tag_of] : entity_of) {
      tag_of = ++next;
      entity_physicals[{std::get<0>(key), tag_of}] = std::get<2>(key);
    }
    std::map<std::tuple<int, int, int>, std::size_t> block_of;  // (dim, entity, type)
    std::vector<RawElementBlock> blocks;
    for (std::size_t i = 0; i < n; ++i) {
      if (merged[i]) continue;
      const V2Element& e = v2_elems_[i];
      const MshElementType* t = msh_element_type(e.type);
      const int entity = entity_of.at(Key{t->dim, e.elementary, phys[i]});
      auto [it, added] = block_of.emplace(std::make_tuple(t->dim, entity, e.type), blocks.size());
      if (added) {
        RawElementBlock b;
        b.entity_dim = t->dim;
        b.entity_tag = entity;
        b.type = e.type;
        blocks.push_back(std::move(b));
      }
      RawElementBlock& b = blocks[it->second];
      b.tags.push_back(e.tag);
      b.offsets.push_back(e.position);
      b.nodes.insert(b.nodes.end(), v2_nodes_.begin() + static_cast<long>(e.first_node),
                     v2_nodes_.begin() + static_cast<long>(e.first_node + t->nodes));
    }
    order_blocks(blocks);
    raw_.blocks = std::move(blocks);
    raw_.groups = groups_of(entity_physicals);
  }
};

}  // namespace

RawModel parse_msh(std::string_view bytes, const std::string& source) {
  return Parser(bytes, source).run();
}

Mesh read_msh(std::string_view bytes, const std::string& source) {
  return assemble_mesh(parse_msh(bytes, source), source);
}

}  // namespace cdem
