// Checkpoints (docs/checkpoint.md): the complete state of a run as named records, written to a
// versioned binary file and read back bit for bit.
//
// The records are those of a StateArchive (core/state_archive.hpp).
//
// File format, version 1 (all integers little-endian, as the mark says):
//   header  "CDEMCKPT" (8 bytes), u32 version = 1, u32 endianness mark 0x01020304,
//           u64 record count, u32 CRC-32 (zlib's crc32) of the 24 bytes before it
//   record  u32 name length, name bytes, u32 element size, u64 element count,
//           u32 CRC-32 of the record's bytes from the name length to the end of its payload,
//           payload (element size x element count bytes)
//   trailer "CKPTEND!" (8 bytes), u64 total file size
// A file is accepted only when the header, every record's checksum and the trailer check out.
#pragma once
#include <string>

#include "cdem/core/state_archive.hpp"

namespace cdem {

// Writes the archive's records to `path` atomically (path.tmp, then rename). Throws
// std::runtime_error naming the file on any write failure; the previous file is then untouched.
void write_checkpoint(const std::string& path, const StateArchive& ar);

// Reads and checks a checkpoint file; the archive is in loading mode. Throws CheckpointError
// naming the file and what is wrong (truncated, checksum, version, endianness).
StateArchive read_checkpoint(const std::string& path);

}  // namespace cdem
