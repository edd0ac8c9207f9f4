#include "cdem/core/resources.hpp"

#include <fmt/format.h>
#include <sched.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

namespace cdem {
namespace {

// A whole-token unsigned integer, or 0.
std::uint64_t parse_u64(const std::string& s) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && end == s.data() + s.size() ? v : 0;
}

std::string first_line(const char* path) {
  std::ifstream f(path);
  std::string line;
  if (f) std::getline(f, line);
  while (!line.empty() && (line.back() == '\n' || line.back() == ' ')) line.pop_back();
  return line;
}

}  // namespace

AvailableMemory available_memory() {
  AvailableMemory m;
  if (const char* env = std::getenv("CDEM_MEMORY_AVAILABLE")) {
    m.bytes = parse_u64(env);
    m.source = "CDEM_MEMORY_AVAILABLE";
    if (m.bytes > 0) return m;
  }
  {
    std::ifstream f("/proc/meminfo");
    std::string key;
    std::uint64_t kb = 0;
    std::string unit;
    while (f >> key >> kb) {
      std::getline(f, unit);
      if (key == "MemAvailable:") {
        m.bytes = kb * 1024;
        m.source = "MemAvailable in /proc/meminfo";
        break;
      }
    }
  }
  // cgroup v2: the limit of the program's own group, when it has one.
  const std::string max = first_line("/sys/fs/cgroup/memory.max");
  const std::uint64_t limit = parse_u64(max);
  if (limit > 0) {
    const std::uint64_t used = parse_u64(first_line("/sys/fs/cgroup/memory.current"));
    const std::uint64_t left = limit > used ? limit - used : 0;
    if (m.bytes == 0 || left < m.bytes) {
      m.bytes = left;
      m.source = "the cgroup memory limit (/sys/fs/cgroup/memory.max)";
    }
  }
  return m;
}

int available_processors() {
  // The processors this process may run on (its affinity mask), like omp_get_num_procs.
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

std::string format_bytes(double bytes) {
  if (bytes >= 1e12) return fmt::format("{:.3g} TB", bytes / 1e12);
  if (bytes >= 1e9) return fmt::format("{:.3g} GB", bytes / 1e9);
  if (bytes >= 1e6) return fmt::format("{:.3g} MB", bytes / 1e6);
  if (bytes >= 1e3) return fmt::format("{:.3g} kB", bytes / 1e3);
  return fmt::format("{:.0f} B", bytes);
}

}  // namespace cdem
