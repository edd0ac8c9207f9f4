#include "cdem/io/checkpoint.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <fstream>
#include <iterator>

#include "cdem/io/atomic_file.hpp"

namespace cdem {
namespace {

static_assert(std::endian::native == std::endian::little,
              "checkpoints store native bytes and declare little-endian");

constexpr char kMagic[8] = {'C', 'D', 'E', 'M', 'C', 'K', 'P', 'T'};
constexpr char kTrailer[8] = {'C', 'K', 'P', 'T', 'E', 'N', 'D', '!'};
// 2: energy.csv gained products_kinetic (a run continues its CSV files, so their layout is part
// of the format).
constexpr std::uint32_t kVersion = 3;  // 3: blocks in Hilbert order (mesh_order.hpp)
constexpr std::uint32_t kEndianMark = 0x01020304u;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + 4;

// zlib's CRC-32, continued from c (0 to start).
std::uint32_t crc(const void* p, std::size_t n, std::uint32_t c = 0) {
  const auto* b = static_cast<const Bytef*>(p);
  while (n > 0) {  // zlib's length is a uInt: feed large payloads in pieces
    const auto k = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    c = static_cast<std::uint32_t>(::crc32(c, b, k));
    b += k;
    n -= k;
  }
  return c;
}

template <class T>
void append(std::string& s, T x) {
  s.append(reinterpret_cast<const char*>(&x), sizeof(T));
}

// Reads values from the file's bytes, refusing to run past the end.
struct Cursor {
  const std::string& path;
  const std::vector<unsigned char>& b;
  std::size_t at = 0;
  void need(std::size_t n, const char* what) const {
    if (n > b.size() - at)
      throw CheckpointError(fmt::format("checkpoint '{}' is truncated: {} at byte {} needs {} bytes, "
                                        "{} left",
                                        path, what, at, n, b.size() - at));
  }
  template <class T>
  T take(const char* what) {
    need(sizeof(T), what);
    T x;
    std::memcpy(&x, b.data() + at, sizeof(T));
    at += sizeof(T);
    return x;
  }
};

}  // namespace

void write_checkpoint(const std::string& path, const StateArchive& ar) {
  AtomicFile f(path);
  std::string head(kMagic, 8);
  append(head, kVersion);
  append(head, kEndianMark);
  append(head, static_cast<std::uint64_t>(ar.records().size()));
  append(head, crc(head.data(), head.size()));
  f.write(head);
  std::uint64_t total = head.size();
  for (const auto& [name, r] : ar.records()) {
    std::string h;
    append(h, static_cast<std::uint32_t>(name.size()));
    h += name;
    append(h, r.elem_size);
    append(h, r.count);
    const std::uint32_t c = crc(r.bytes.data(), r.bytes.size(), crc(h.data(), h.size()));
    append(h, c);
    f.write(h);
    f.write(r.bytes.data(), r.bytes.size());
    total += h.size() + r.bytes.size();
  }
  std::string tail(kTrailer, 8);
  append(tail, total + 16);
  f.write(tail);
  f.commit();
}

StateArchive read_checkpoint(const std::string& path) {
  std::vector<unsigned char> bytes;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw CheckpointError(fmt::format("cannot open checkpoint '{}'", path));
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) throw CheckpointError(fmt::format("cannot read checkpoint '{}'", path));
  }
  Cursor c{path, bytes};
  c.need(kHeaderBytes, "the header");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw CheckpointError(fmt::format("'{}' is not a cdemblast checkpoint (no CDEMCKPT mark)", path));
  c.at = 8;
  const auto version = c.take<std::uint32_t>("the version");
  const auto mark = c.take<std::uint32_t>("the endianness mark");
  const auto n_records = c.take<std::uint64_t>("the record count");
  const auto head_crc = c.take<std::uint32_t>("the header checksum");
  if (crc(bytes.data(), 24) != head_crc)
    throw CheckpointError(fmt::format("checkpoint '{}': the header's checksum is wrong (corrupted)", path));
  if (mark != kEndianMark)
    throw CheckpointError(fmt::format("checkpoint '{}' was written on a machine of other endianness", path));
  if (version != kVersion)
    throw CheckpointError(fmt::format("checkpoint '{}' has format version {}, this cdemblast reads "
                                      "version {}",
                                      path, version, kVersion));
  StateArchive ar(true);
  for (std::uint64_t k = 0; k < n_records; ++k) {
    const std::size_t start = c.at;
    const auto len = c.take<std::uint32_t>("a record's name length");
    if (len == 0 || len > kMaxRecordName)
      throw CheckpointError(fmt::format("checkpoint '{}': record {} at byte {} has a name of {} bytes "
                                        "(corrupted)",
                                        path, k, start, len));
    c.need(len, "a record's name");
    std::string name(reinterpret_cast<const char*>(bytes.data() + c.at), len);
    c.at += len;
    StateRecord r;
    r.elem_size = c.take<std::uint32_t>("a record's element size");
    r.count = c.take<std::uint64_t>("a record's element count");
    const std::size_t head_end = c.at;
    const auto want = c.take<std::uint32_t>("a record's checksum");
    if (r.elem_size == 0 || r.count > (bytes.size() - c.at) / r.elem_size)
      throw CheckpointError(fmt::format("checkpoint '{}' is truncated or corrupted: record '{}' "
                                        "claims {} x {} bytes, {} are left",
                                        path, name, r.count, r.elem_size, bytes.size() - c.at));
    const std::size_t n = r.elem_size * r.count;
    const std::uint32_t got = crc(bytes.data() + c.at, n, crc(bytes.data() + start, head_end - start));
    if (got != want)
      throw CheckpointError(fmt::format("checkpoint '{}': the checksum of record '{}' is wrong "
                                        "(corrupted)",
                                        path, name));
    r.bytes.assign(bytes.begin() + static_cast<std::ptrdiff_t>(c.at),
                   bytes.begin() + static_cast<std::ptrdiff_t>(c.at + n));
    c.at += n;
    ar.records()[name] = std::move(r);
  }
  c.need(16, "the trailer");
  if (std::memcmp(bytes.data() + c.at, kTrailer, 8) != 0)
    throw CheckpointError(fmt::format("checkpoint '{}': no end mark after the last record (corrupted)", path));
  c.at += 8;
  if (c.take<std::uint64_t>("the file size") != bytes.size() || c.at != bytes.size())
    throw CheckpointError(fmt::format("checkpoint '{}': the file size does not match its trailer", path));
  return ar;
}

}  // namespace cdem
