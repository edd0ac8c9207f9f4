// libFuzzer target: the case parser (case text checks, toml11, validation into a Case).
#include <spdlog/spdlog.h>

#include "fuzz_bodies.hpp"

// Warnings about odd but legal input would be printed for most inputs: logging is off.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cdem::fuzz::case_input(data, size);
  return 0;
}
