// The bodies of the two fuzz targets, shared with the replay test of the corpora and the crash
// regressions (tests/unit/test_fuzz_regressions.cpp), so that the Release and sanitizer builds
// run every kept input through exactly what the fuzzer ran.
//
// An input is handled correctly when it is accepted or refused with an InputError (a MeshError
// for meshes); any other exception, a crash, a sanitizer report or a hang is a bug. A broken
// property (an accepted case whose resolved form no longer parses) aborts.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/io/case.hpp"
#include "cdem/mesh/msh_reader.hpp"
#include "cdem/mesh/topology.hpp"

namespace cdem::fuzz {

// A case file. When the input starts with "#set " its first line is also applied as a --set
// override ("#set simulation.end_time=1"), so overrides get fuzzed too.
inline void case_input(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> overrides;
  if (text.substr(0, 5) == "#set ") {
    const std::size_t nl = text.find('\n');
    overrides.emplace_back(text.substr(5, nl == std::string_view::npos ? text.size() - 5 : nl - 5));
  }
  Case c;
  try {
    c = parse_case(text, "fuzz.toml", overrides);
  } catch (const InputError&) {
    return;
  }
  // Accepted: its resolved form (what a run writes next to its results) must parse again.
  const std::string resolved = resolved_case_toml(c);
  try {
    (void)parse_case(resolved, "fuzz.resolved.toml");
  } catch (const InputError& e) {
    std::fprintf(stderr, "the resolved case does not parse again: %s\n--- resolved case:\n%s\n",
                 e.what(), resolved.c_str());
    std::abort();
  }
}

// A mesh file; a mesh the reader accepts is also split into CDEM blocks and interfaces (one
// material for every region), which is what a case does with it next.
inline void msh_input(const std::uint8_t* data, std::size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  Mesh mesh;
  try {
    mesh = read_msh(bytes, "mesh file 'fuzz.msh'");
  } catch (const MeshError&) {
    return;
  }
  BlockMaterial rock;
  rock.name = "rock";
  rock.density = 2600;
  rock.youngs = 30e9;
  rock.poisson = 0.25;
  rock.regions = mesh.region_names;
  InterfaceMaterial bond;
  bond.name = "bond";
  bond.is_default = true;
  try {
    (void)build_model(mesh, {rock}, {bond}, "fuzz.toml");
  } catch (const InputError&) {
  }
}

}  // namespace cdem::fuzz
