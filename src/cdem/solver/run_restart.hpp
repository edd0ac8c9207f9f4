// Restart helpers of the run loop (run_restart.cpp).
#pragma once
#include <string>

#include "cdem/core/state_archive.hpp"
#include "cdem/io/case.hpp"

namespace cdem {

// The newest checkpoint of `dir` that reads and checks out; a refused one is reported and the
// one before it is tried. `option` names the command-line option in messages.
StateArchive load_last_checkpoint(const std::string& dir, bool quiet, const char* option = "--restart");

// The checkpoint's case against this one (`signature`: restart_signature of it): only the
// schedule keys may differ. Throws InputError naming the first line that differs.
void check_checkpoint_case(StateArchive& ckpt, const Case& c, const std::string& dir,
                           const std::string& signature);

}  // namespace cdem
