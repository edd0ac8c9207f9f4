#pragma once
// Test helpers shared by the mesh-file tests: the bundled meshes and a scratch directory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cdem/mesh/gmsh_io.hpp"

namespace cdem::testing_files {

// A mesh of tests/data/meshes/.
inline std::string data(const std::string& name) {
  return std::string(CDEM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// A fresh scratch directory per test: <tmp>/<prefix><pid>_<test name>.
inline std::filesystem::path scratch_dir(const std::string& prefix) {
  namespace fs = std::filesystem;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 (prefix + std::to_string(::getpid()) + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Two generated meshes to write and read back: a 2D quad rectangle with a slot hole (element
// size h2d) and a 3D tet box.
inline std::vector<GenerateSpec> round_trip_specs(double h2d) {
  GenerateSpec s2;
  s2.shape = "rectangle";
  s2.size = {2, 1, 0};
  s2.element_size = h2d;
  s2.quads = true;
  s2.holes = {HoleSpec{{1, 1, 0}, 0.05, {0, -1, 0}, 0.4, "charge"}};
  GenerateSpec s3;
  s3.shape = "box";
  s3.size = {1, 0.5, 0.5};
  s3.element_size = 0.25;
  return {s2, s3};
}

}  // namespace cdem::testing_files
