// libFuzzer target: the MSH reader (parse_msh, assemble_mesh, check_mesh) and the CDEM split.
#include <spdlog/spdlog.h>

#include "fuzz_bodies.hpp"

// Warnings about odd but legal input would be printed for most inputs: logging is off.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cdem::fuzz::msh_input(data, size);
  return 0;
}
