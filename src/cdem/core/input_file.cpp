#include "cdem/core/input_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "cdem/core/error.hpp"
#include "cdem/core/resources.hpp"

namespace cdem {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "it is a directory";
  if (S_ISFIFO(mode)) return "it is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode)) return "it is a character device (such as /dev/zero), not a regular file";
  if (S_ISBLK(mode)) return "it is a block device, not a regular file";
  if (S_ISSOCK(mode)) return "it is a socket, not a regular file";
  return "it is not a regular file";
}

// Closes the descriptor on every path.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string read_input_file(const std::string& path, const std::string& what,
                            std::uint64_t max_bytes, const std::string& limit_reason) {
  const std::string why_limit = limit_reason.empty() ? "" : " (" + limit_reason + ")";
  auto fail = [&](const std::string& why) -> void {
    throw InputError(fmt::format("cannot open {} '{}': {}", what, path, why));
  };
  // O_NONBLOCK: opening a FIFO without a writer returns at once (fstat then refuses it).
  Fd f;
  f.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f.fd < 0) {
    const int err = errno;
    // A directory opens read-only on Linux; anything else failing is reported as the OS says.
    fail(std::strerror(err));
  }
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) fail(std::strerror(errno));
  if (!S_ISREG(st.st_mode)) fail(kind_of(st.st_mode));
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes)
    fail(fmt::format("it is {} long, more than the {} read at most{}",
                     format_bytes(static_cast<double>(st.st_size)),
                     format_bytes(static_cast<double>(max_bytes)), why_limit));
  // Back to blocking reads for a regular file (O_NONBLOCK has no effect on them anyway).
  std::string out;
  out.reserve(static_cast<std::size_t>(st.st_size));
  char buf[1 << 16];
  while (true) {
    const ssize_t n = ::read(f.fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::strerror(errno));
    }
    if (n == 0) break;
    if (out.size() + static_cast<std::size_t>(n) > max_bytes)
      fail(fmt::format("it holds more than the {} read at most{}",
                       format_bytes(static_cast<double>(max_bytes)), why_limit));
    out.append(buf, static_cast<std::size_t>(n));
  }
  return out;
}

FileLimit max_mesh_file_bytes() {
  constexpr std::uint64_t cap = std::uint64_t{16} << 30;
  const AvailableMemory mem = available_memory();
  if (mem.bytes == 0 || mem.bytes / 4 >= cap) return {cap, "the largest mesh file cdemblast reads"};
  return {mem.bytes / 4, fmt::format("a quarter of the {} of memory available, {}",
                                     format_bytes(static_cast<double>(mem.bytes)), mem.source)};
}

}  // namespace cdem
