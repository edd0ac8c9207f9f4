// libFuzzer target: the MSH reader (parse_msh, assemble_mesh, check_mesh) and the CDEM split.
#include "fuzz_bodies.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cdem::fuzz::msh_input(data, size);
  return 0;
}
