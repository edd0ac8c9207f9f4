// libFuzzer target: the case parser (case text checks, toml11, validation into a Case).
#include "fuzz_bodies.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cdem::fuzz::case_input(data, size);
  return 0;
}
