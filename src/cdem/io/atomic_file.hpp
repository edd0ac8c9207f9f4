// A file written through `path.tmp` and renamed onto `path` (atomic on POSIX file systems): a
// reader sees the old file or the new one, never a half-written one.
#pragma once
#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cdem {

inline std::string errno_text() { return std::strerror(errno); }

// A file written through `path.tmp` and renamed onto `path` by commit(); removed if not
// committed. Every failure throws std::runtime_error naming `path`.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path) : path_(path), tmp_(path + ".tmp") {
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_)
      throw std::runtime_error(
          fmt::format("cannot write '{}': cannot create '{}': {}", path_, tmp_, errno_text()));
    std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() {
    if (file_) {
      std::fclose(file_);
      std::remove(tmp_.c_str());
    }
  }

  void write(const void* data, std::size_t size) {
    if (size > 0 && std::fwrite(data, 1, size, file_) != size)
      throw std::runtime_error(
          fmt::format("cannot write '{}': write to '{}' failed: {}", path_, tmp_, errno_text()));
  }
  void write(const std::string& s) { write(s.data(), s.size()); }

  void commit() {
    std::string why;
    if (std::fflush(file_) != 0) why = errno_text();
    if (std::fclose(file_) != 0 && why.empty()) why = errno_text();
    file_ = nullptr;
    if (!why.empty()) {
      std::remove(tmp_.c_str());
      throw std::runtime_error(
          fmt::format("cannot write '{}': closing '{}' failed: {}", path_, tmp_, why));
    }
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      why = errno_text();
      std::remove(tmp_.c_str());
      throw std::runtime_error(
          fmt::format("cannot write '{}': renaming '{}' failed: {}", path_, tmp_, why));
    }
  }

 private:
  std::string path_, tmp_;
  std::FILE* file_ = nullptr;
};

}  // namespace cdem
