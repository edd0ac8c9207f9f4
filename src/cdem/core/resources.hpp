// What this machine can give a run: available memory and processors, read before large work
// starts so that a case asking for more is refused with a message instead of swapping or being
// killed (docs/input_safety.md).
#pragma once
#include <cstdint>
#include <string>

namespace cdem {

struct AvailableMemory {
  std::uint64_t bytes = 0;  // 0: unknown
  std::string source;       // where the figure comes from, for messages
};

// Memory the program may still use: MemAvailable of /proc/meminfo, lowered to the cgroup's
// memory.max - memory.current when the program runs in a memory-limited cgroup (v2). The
// environment variable CDEM_MEMORY_AVAILABLE (bytes) replaces both (tests, batch systems).
AvailableMemory available_memory();

// Processors this process may run on (its CPU affinity, as omp_get_num_procs counts them).
int available_processors();

// "1.2 GB", "340 MB": decimal units, for messages.
std::string format_bytes(double bytes);

}  // namespace cdem
