// Run directories that cannot mix, checkpoint files, and clean interruption
// (docs/checkpoint.md).
//
// - A run holds an exclusive lock (flock) on `<dir>/.lock` while it writes into the directory:
//   a second run into it is refused at once. The lock goes with the process, so a killed run
//   leaves no stale lock.
// - A new run into a directory that holds results (summary.json, fields.pvd, histories,
//   checkpoints) is refused unless asked to overwrite them; then the old results are removed
//   first, so no file of the old run survives beside the new ones.
// - Checkpoints are `<dir>/checkpoints/ckpt_<step>.cdemckpt`; the newest two are kept.
// - SIGINT and SIGTERM ask the run loop to stop after the current step (stop_signal()); a second
//   signal ends the process at once.
#pragma once
#include <string>
#include <vector>

namespace cdem {

class RunDirLock {
 public:
  // Creates `dir` if needed and locks it; throws InputError naming the directory (and the pid
  // that holds it) when another run holds the lock.
  explicit RunDirLock(const std::string& dir);
  ~RunDirLock();
  RunDirLock(const RunDirLock&) = delete;
  RunDirLock& operator=(const RunDirLock&) = delete;

 private:
  int fd_ = -1;
};

// The results a run writes into its directory that are present in `dir` (names relative to it).
std::vector<std::string> run_results_in(const std::string& dir);

// Before a new run (not a restart): refuses a directory with results (InputError naming them and
// the options) unless `overwrite`, which removes them.
void prepare_run_dir(const std::string& dir, bool overwrite);

// A new run id: 16 hexadecimal digits from the clock, the pid and a random device.
std::string new_run_id();

std::string checkpoint_dir(const std::string& run_dir);
std::string checkpoint_path(const std::string& run_dir, long long step);
// The checkpoint files of a run directory, newest (highest step) first.
std::vector<std::string> list_checkpoints(const std::string& run_dir);
// Removes all but the newest `keep` checkpoints.
void prune_checkpoints(const std::string& run_dir, std::size_t keep);

// SIGINT / SIGTERM: the first sets the stop flag, a second exits at once (128 + signal).
void install_stop_signals();
void restore_default_signals();
int stop_signal();  // 0, or the signal that asked to stop

}  // namespace cdem
