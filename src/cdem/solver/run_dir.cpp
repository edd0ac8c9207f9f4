#include "cdem/solver/run_dir.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <random>

#include "cdem/core/error.hpp"

namespace cdem {
namespace fs = std::filesystem;

namespace {
// What a run writes into its directory (RunWriter, run_case, cdemblast report).
const char* const kResults[] = {"summary.json", "fields.pvd",    "cracks.pvd",   "energy.csv",
                                "monitors.csv", "fracture.csv",  "reactions.csv", "charges.csv",
                                "grading.csv",  "case.resolved.toml", "fields",    "cracks",
                                "fragments",    "checkpoints",   "report"};
// Only these mean that the directory holds a run (a directory with just an empty `fields/`
// left by mkdir does not).
const char* const kRunMarks[] = {"summary.json", "fields.pvd", "energy.csv", "checkpoints"};

volatile std::sig_atomic_t g_stop = 0;

extern "C" void on_stop_signal(int sig) {
  if (g_stop != 0) _exit(128 + sig);  // a second signal: at once
  g_stop = sig;
}
}  // namespace

RunDirLock::RunDirLock(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(fmt::format("cannot create the output directory '{}': {}", dir, ec.message()));
  const std::string path = (fs::path(dir) / ".lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(fmt::format("cannot write into '{}': {}", dir, std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    char buf[32] = {};
    const auto n = ::pread(fd_, buf, sizeof buf - 1, 0);
    ::close(fd_);
    fd_ = -1;
    throw InputError(fmt::format("'{}' is in use by another cdemblast run{}: two runs cannot write "
                                 "into one directory; choose another --out",
                                 dir, n > 0 ? fmt::format(" (pid {})", std::string(buf, static_cast<std::size_t>(n))) : ""));
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(fd_, 0) == 0 && ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
    // the pid is only for the message of a refused second run
  }
}

RunDirLock::~RunDirLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

std::vector<std::string> run_results_in(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const char* r : kResults)
    if (fs::exists(fs::path(dir) / r, ec)) out.emplace_back(r);
  return out;
}

void prepare_run_dir(const std::string& dir, bool overwrite) {
  std::error_code ec;
  bool is_run = false;
  for (const char* r : kRunMarks) is_run = is_run || fs::exists(fs::path(dir) / r, ec);
  if (!is_run) return;
  const auto found = run_results_in(dir);
  if (!overwrite) {
    std::string list;
    for (std::size_t i = 0; i < found.size() && i < 6; ++i) list += (i ? ", " : "") + found[i];
    throw InputError(fmt::format("'{}' holds the results of another run ({}{}): pass --overwrite to "
                                 "remove them and run anew, or --restart {} to continue that run",
                                 dir, list, found.size() > 6 ? ", ..." : "", dir));
  }
  for (const auto& r : found) {
    fs::remove_all(fs::path(dir) / r, ec);
    if (ec) throw InputError(fmt::format("--overwrite: cannot remove '{}': {}", (fs::path(dir) / r).string(), ec.message()));
  }
}

std::string new_run_id() {
  std::random_device rd;
  const auto now = static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  std::uint64_t x = now ^ (static_cast<std::uint64_t>(::getpid()) << 40) ^
                    (static_cast<std::uint64_t>(rd()) << 20) ^ static_cast<std::uint64_t>(rd());
  x ^= x >> 33;  // mix (splitmix64 finaliser)
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  return fmt::format("{:016x}", x);
}

std::string checkpoint_dir(const std::string& run_dir) { return (fs::path(run_dir) / "checkpoints").string(); }

std::string checkpoint_path(const std::string& run_dir, long long step) {
  return (fs::path(checkpoint_dir(run_dir)) / fmt::format("ckpt_{:012d}.cdemckpt", step)).string();
}

std::vector<std::string> list_checkpoints(const std::string& run_dir) {
  std::vector<std::string> out;
  std::error_code ec;
  const fs::path d = checkpoint_dir(run_dir);
  if (!fs::is_directory(d, ec)) return out;
  for (const auto& e : fs::directory_iterator(d, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() == 26 && name.rfind("ckpt_", 0) == 0 && name.ends_with(".cdemckpt") && e.is_regular_file(ec))
      out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end(), std::greater<>());  // fixed-width step: newest first
  return out;
}

void prune_checkpoints(const std::string& run_dir, std::size_t keep) {
  const auto all = list_checkpoints(run_dir);
  std::error_code ec;
  for (std::size_t i = keep; i < all.size(); ++i) fs::remove(all[i], ec);
}

void install_stop_signals() {
  g_stop = 0;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void restore_default_signals() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

int stop_signal() { return static_cast<int>(g_stop); }

}  // namespace cdem
