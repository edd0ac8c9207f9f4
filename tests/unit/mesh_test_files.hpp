#pragma once
// Test helpers shared by the mesh-file tests: the bundled meshes and a scratch directory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

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

}  // namespace cdem::testing_files
