// Every input kept under tests/fuzz (the seed corpora and each crashing input found by fuzzing,
// tests/fuzz/regressions) run through the fuzz targets' own bodies (tests/fuzz/fuzz_bodies.hpp):
// accepted or refused with an InputError, never another exception. The sanitizer build
// (make sanitize-test) runs them under AddressSanitizer and UBSan.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fuzz/fuzz_bodies.hpp"

namespace cdem {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> files_in(const std::vector<std::string>& dirs) {
  std::vector<fs::path> out;
  for (const auto& d : dirs) {
    const fs::path dir = fs::path(CDEM_SOURCE_DIR) / "tests" / "fuzz" / d;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file()) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Runs `body` on every file; odd inputs log warnings, which are silenced meanwhile.
template <class Body>
void replay(const std::vector<std::string>& dirs, Body body, std::size_t at_least) {
  const auto files = files_in(dirs);
  EXPECT_GE(files.size(), at_least);
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::off);
  for (const auto& f : files) {
    const std::string b = bytes_of(f);
    EXPECT_NO_THROW(body(reinterpret_cast<const std::uint8_t*>(b.data()), b.size())) << f;
  }
  spdlog::set_level(level);
}

TEST(FuzzRegressions, CaseCorpusAndCrashes) {
  replay({"corpus_case", "regressions/case"}, fuzz::case_input, 30);
}

TEST(FuzzRegressions, MshCorpusAndCrashes) {
  replay({"corpus_msh", "regressions/msh"}, fuzz::msh_input, 30);
}

}  // namespace
}  // namespace cdem
