// The restart's case signature of a checkpoint written before a case key existed
// (upgrade_signature, solver/run.hpp): the missing line is put in with the value that reproduces
// the code that wrote it, in the place the resolved case has it.
#include <gtest/gtest.h>

#include <string>

#include "cdem/io/case.hpp"
#include "cdem/solver/run.hpp"

namespace cdem {
namespace {

// A signature as the code before simulation.release_angle wrote it: today's resolved case
// without that line.
std::string without_line(std::string text, const std::string& key) {
  const auto p = text.find("\n" + key + " = ");
  EXPECT_NE(p, std::string::npos) << key;
  if (p == std::string::npos) return text;
  const auto e = text.find('\n', p + 1);
  text.erase(p + 1, e - p);
  return text;
}

const std::string kCase =
    "[mesh.generate]\nshape = \"rectangle\"\nsize = [1.0, 1.0]\nelement_size = 0.25\n"
    "[simulation]\nend_time = 1e-3\n"
    "[[material]]\nname = \"r\"\nregions = [\"rock\"]\ndensity = 2600\nyoungs_modulus = 3e10\n"
    "poisson_ratio = 0.25\n";

TEST(RestartSignature, OldCheckpointReadsAsReleaseAngle180) {
  const Case c = parse_case(kCase, "c.toml");
  const std::string old_sig = without_line(resolved_case_toml(c), "release_angle");
  ASSERT_EQ(old_sig.find("\nrelease_angle = "), std::string::npos);
  // the old signature reads as the case with release_angle = 180, line for line
  const Case c180 = parse_case(kCase, "c.toml", {"simulation.release_angle=180"});
  EXPECT_EQ(upgrade_signature(old_sig), resolved_case_toml(c180));
  // and so differs from the default case (28.65 degrees) at that key
  EXPECT_NE(upgrade_signature(old_sig), resolved_case_toml(c));
  // a signature that has the line is left as it is
  EXPECT_EQ(upgrade_signature(resolved_case_toml(c)), resolved_case_toml(c));
}

}  // namespace
}  // namespace cdem
