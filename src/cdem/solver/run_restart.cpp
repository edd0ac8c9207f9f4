// Restarts (run.hpp, run_restart.hpp): the case signature a checkpoint keeps and its check, and
// the newest checkpoint of a run directory that reads.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <string>

#include "cdem/core/error.hpp"
#include "cdem/io/checkpoint.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/run_dir.hpp"
#include "cdem/solver/run_restart.hpp"
#include "cdem/solver/run_state.hpp"

namespace cdem {

// (run.hpp)
std::string upgrade_signature(std::string sig) {
  if (sig.find("\nrelease_angle = ") == std::string::npos) {
    const auto p = sig.find("\nrelease_distance_factor = ");
    const auto e = p == std::string::npos ? p : sig.find('\n', p + 1);
    if (e != std::string::npos) sig.insert(e + 1, "release_angle = 180\n");
  }
  // contact.candidates was written only when "cracked" (not the default then) before 7 Dec 2026;
  // now always, after stiffness_factor and friction (both written only in [contact], friction
  // only right after stiffness_factor), and its default is "cracked"
  if (const auto ct = sig.find("\n[contact]\n"); ct != std::string::npos && sig.find("\ncandidates = ", ct) == std::string::npos) {
    const auto sf = sig.find("\nstiffness_factor = ", ct);
    auto e = sf == std::string::npos ? sf : sig.find('\n', sf + 1);
    if (e != std::string::npos && sig.compare(e + 1, 11, "friction = ") == 0) e = sig.find('\n', e + 1);
    if (e != std::string::npos) sig.insert(e + 1, "candidates = \"released\"\n");
  }
  // contact.passivity did not exist before 7 Dec 2026 (those runs ran without it); it is written
  // always, right after candidates
  if (const auto ct = sig.find("\n[contact]\n"); ct != std::string::npos && sig.find("\npassivity = ", ct) == std::string::npos) {
    const auto cd = sig.find("\ncandidates = ", ct);
    const auto e = cd == std::string::npos ? cd : sig.find('\n', cd + 1);
    if (e != std::string::npos) sig.insert(e + 1, "passivity = false\n");
  }
  // [delays] was written in the hash order of the case's table before 6 Dec 2026; now by key
  const auto d = sig.find("\n[delays]\n");
  if (d != std::string::npos) {
    const std::size_t begin = d + 10;
    std::size_t end = begin;
    std::vector<std::pair<std::string, std::string>> lines;  // (key, line)
    while (end < sig.size() && sig[end] == '"') {
      const auto nl = sig.find('\n', end);
      const std::string line = sig.substr(end, (nl == std::string::npos ? sig.size() : nl) - end);
      std::string key;  // (unescaped as written by resolved_case_toml: \" and \\)
      for (std::size_t k = 1; k < line.size() && line[k] != '"'; ++k) key += line[k] == '\\' && k + 1 < line.size() ? line[++k] : line[k];
      lines.emplace_back(key, line);
      end = nl == std::string::npos ? sig.size() : nl + 1;
    }
    std::sort(lines.begin(), lines.end());
    std::string sorted;
    for (const auto& [key, line] : lines) sorted += line + "\n";
    if (sorted.size() == end - begin) sig.replace(begin, end - begin, sorted);
  }
  return sig;
}

std::string restart_signature(const Case& c) {
  Case k = c;
  k.end_time = 1;
  k.output_interval = 0;
  k.output_times.clear();
  k.history_interval = 0;
  k.threads = 0;
  k.max_steps = 0;
  k.checkpoint_interval = 0;
  k.checkpoint_wall_interval = 0;
  k.contact.sleep = true;  // (the same results either way: contact.hpp)
  // without its comments (they name the file the case was read from)
  std::string out, line;
  const std::string text = resolved_case_toml(k);
  for (std::size_t i = 0; i < text.size();) {
    const auto e = std::min(text.find('\n', i), text.size());
    line = text.substr(i, e - i);
    if (line.empty() || line[0] != '#') out += line + "\n";
    i = e + 1;
  }
  return out;
}

namespace {

// The first line where two texts differ, for the message of a refused restart.
std::string first_difference(const std::string& a, const std::string& b) {
  std::size_t i = 0, la = 0;
  while (i < a.size() && i < b.size() && a[i] == b[i]) {
    if (a[i] == '\n') la = i + 1;
    ++i;
  }
  auto line = [](const std::string& s, std::size_t from) {
    const auto e = s.find('\n', from);
    return s.substr(from, e == std::string::npos ? std::string::npos : e - from);
  };
  return fmt::format("'{}' (checkpoint: '{}')", line(b, la), line(a, la));
}

}  // namespace

// The newest checkpoint of `dir` that reads and checks out; a refused one is reported and the
// one before it is tried.
StateArchive load_last_checkpoint(const std::string& dir, bool quiet, const char* option) {
  const auto files = list_checkpoints(dir);
  if (files.empty())
    throw InputError(fmt::format("{} {}: no checkpoint in '{}' (a run writes one every "
                                 "simulation.checkpoint_wall_interval, at its end and when "
                                 "interrupted)",
                                 option, dir, checkpoint_dir(dir)));
  std::string why;
  for (const auto& f : files) {
    try {
      StateArchive ar = read_checkpoint(f);
      if (!quiet) spdlog::info("restarting from {}", f);
      return ar;
    } catch (const CheckpointError& e) {
      spdlog::warn("{}; trying the one before it", e.what());
      why += fmt::format("\n  {}", e.what());
    }
  }
  throw InputError(fmt::format("{} {}: no readable checkpoint:{}", option, dir, why));
}

// The checkpoint's case against this one: only the schedule keys may differ.
void check_checkpoint_case(StateArchive& ckpt, const Case& c, const std::string& dir,
                           const std::string& signature) {
  std::string sig;
  ckpt.io("run.case_signature", sig);
  sig = upgrade_signature(std::move(sig));
  if (sig != signature) {
    const std::string at = first_difference(sig, signature);
    // (a key a run of before 7 Dec 2026 meets: say how to continue it)
    const bool passivity = at.rfind("'passivity = ", 0) == 0;
    const bool candidates = at.rfind("'candidates = ", 0) == 0;
    throw InputError(fmt::format("{}: the case differs from the one of the checkpointed run in '{}' "
                                 "at {}; only simulation.end_time, output_interval, output_times, "
                                 "history_interval, threads, max_steps, contact.sleep and the checkpoint keys may "
                                 "change for a restart{}",
                                 c.path, dir, at,
                                 passivity ? " (contact.passivity is on by default since 7 Dec 2026; continue a run "
                                             "made without it by adding --set contact.passivity=false)"
                                 : candidates ? " (contact.candidates is \"cracked\" by default since 7 Dec 2026; "
                                                "continue a run made with \"released\" by adding --set "
                                                "'contact.candidates=\"released\"')"
                                              : ""));
  }
}



void load_checkpointed_state(PreparedCase& pc, const Case& c, const std::string& dir) {
  StateArchive ar = load_last_checkpoint(dir, true, "--from");
  check_checkpoint_case(ar, c, dir, restart_signature(c));
  pc.sim.io_state(ar);
  io_state(ar, pc.bars);
  io_state(ar, pc.solids);
}

}  // namespace cdem
