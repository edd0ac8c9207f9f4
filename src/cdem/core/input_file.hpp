// Reading untrusted input files (case files, mesh files): only regular files, of a bounded
// size, read whole into memory before anything parses them.
#pragma once
#include <cstdint>
#include <string>

namespace cdem {

// The whole content of the regular file `path`. `what` names it in messages ("mesh file").
// Throws InputError "cannot open <what> '<path>': <reason>" when the file is missing or
// unreadable, is not a regular file (a directory, a FIFO, a device such as /dev/zero, a socket;
// the file is opened non-blocking and checked with fstat, so a FIFO never blocks), or holds more
// than max_bytes (counted while reading, whatever the file system says its size is).
// `limit_reason` (may be empty) says where max_bytes comes from, for the message.
std::string read_input_file(const std::string& path, const std::string& what,
                            std::uint64_t max_bytes, const std::string& limit_reason = "");

// Largest case file read (bytes). A case file is a few kilobytes; this leaves room for cases
// with thousands of holes and refuses a wrong file (a mesh, an image) at once.
inline constexpr std::uint64_t kMaxCaseFileBytes = 4u << 20;

// Largest mesh file read (bytes): a quarter of the memory available to the program (reading
// and assembling a mesh takes a few times the file's size), at most 16 GiB; and why.
struct FileLimit {
  std::uint64_t bytes = 0;
  std::string reason;
};
FileLimit max_mesh_file_bytes();

}  // namespace cdem
