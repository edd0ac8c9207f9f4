// The restart's case signature of a checkpoint written before a case key existed
// (upgrade_signature, solver/run.hpp): the missing line is put in with the value that reproduces
// the code that wrote it, in the place the resolved case has it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

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

// contact.candidates was written only when "cracked" before its default became "cracked" (7 Dec
// 2026): an old signature without the line was resolved with "released", and reads as that, in
// the place the line has today (after friction when there is one).
TEST(RestartSignature, OldCheckpointReadsAsReleasedCandidates) {
  for (const char* friction : {"", "contact.friction=0.4"}) {
    std::vector<std::string> sets, released = {"contact.candidates=\"released\""};
    if (*friction) sets.push_back(friction), released.push_back(friction);
    const Case c = parse_case(kCase, "c.toml", sets);
    ASSERT_TRUE(c.contact.cracked_faces) << "the default";
    const std::string old_sig = without_line(resolved_case_toml(c), "candidates");
    const Case cr = parse_case(kCase, "c.toml", released);
    EXPECT_EQ(upgrade_signature(old_sig), resolved_case_toml(cr)) << friction;
    EXPECT_NE(upgrade_signature(old_sig), resolved_case_toml(c));
    EXPECT_EQ(upgrade_signature(resolved_case_toml(c)), resolved_case_toml(c));
    EXPECT_EQ(upgrade_signature(resolved_case_toml(cr)), resolved_case_toml(cr));
    // a signature from before both keys reads as the case with both old values
    released.push_back("simulation.release_angle=180");
    EXPECT_EQ(upgrade_signature(without_line(old_sig, "release_angle")),
              resolved_case_toml(parse_case(kCase, "c.toml", released)));
  }
}

// contact.passivity did not exist before 7 Dec 2026; now it is written always, after candidates.
// An old signature ran without it and reads as passivity = false: it differs from today's
// default there (a restart asks for --set contact.passivity=false), and equals the case that
// sets it.
TEST(RestartSignature, OldCheckpointReadsAsNoPassivity) {
  const Case c = parse_case(kCase, "c.toml");
  ASSERT_TRUE(c.contact.passivity) << "the default";
  const std::string resolved = resolved_case_toml(c);
  ASSERT_NE(resolved.find("\ncandidates = \"cracked\"\npassivity = true\n"), std::string::npos);
  const std::string old_sig = without_line(resolved, "passivity");
  const std::string off = resolved_case_toml(parse_case(kCase, "c.toml", {"contact.passivity=false"}));
  EXPECT_EQ(upgrade_signature(old_sig), off);
  EXPECT_NE(upgrade_signature(old_sig), resolved);
  EXPECT_EQ(upgrade_signature(resolved), resolved);
  EXPECT_EQ(upgrade_signature(off), off);
  // from before candidates was written too: both lines put back, in their places, with the
  // values of then
  EXPECT_EQ(upgrade_signature(without_line(old_sig, "candidates")),
            resolved_case_toml(parse_case(kCase, "c.toml", {"contact.passivity=false", "contact.candidates=\"released\""})));
}

// `resume` reads the run's case.resolved.toml, whose [delays] table was written in the order the
// case's table was walked: a hash order, which need not survive writing and reading back. The
// SPEC 5.3 example (three delay groups) then refused to resume ("the case differs ... at
// '"1" = 0'"). The groups are kept in key order, so the resolved case reads back to the same
// signature; a signature written in the old order reads as the sorted one.
TEST(RestartSignature, ResolvedCaseWithDelaysReadsBackTheSame) {
  const std::string text =
      "[mesh.generate]\nshape = \"box\"\nsize = [2.0, 2.0, 2.0]\nelement_size = 0.5\n"
      "[simulation]\nend_time = 1e-3\n"
      "[[material]]\nname = \"r\"\nregions = [\"rock\"]\ndensity = 2600\nyoungs_modulus = 3e10\n"
      "poisson_ratio = 0.25\n"
      "[[explosive]]\nname = \"e\"\ndensity = 1000\ndetonation_velocity = 4000\ndetonation_heat = 4e6\n"
      "[[hole]]\nname = \"h1\"\ngroup = \"1\"\ncollar = [0.5, 0.5, 2.0]\nend = [0.5, 0.5, 0.5]\ndiameter = 0.04\n"
      "[[hole.charge]]\nexplosive = \"e\"\nlength = 1.0\n"
      "[[hole]]\nname = \"h2\"\ngroup = \"2\"\ncollar = [1.5, 0.5, 2.0]\nend = [1.5, 0.5, 0.5]\ndiameter = 0.04\n"
      "[[hole.charge]]\nexplosive = \"e\"\nlength = 1.0\n"
      "[[hole]]\nname = \"h3\"\ngroup = \"3\"\ncollar = [1.5, 1.5, 2.0]\nend = [1.5, 1.5, 0.5]\ndiameter = 0.04\n"
      "[[hole.charge]]\nexplosive = \"e\"\nlength = 1.0\n"
      "[[hole]]\nname = \"h10\"\ngroup = \"10\"\ncollar = [0.5, 1.5, 2.0]\nend = [0.5, 1.5, 0.5]\ndiameter = 0.04\n"
      "[[hole.charge]]\nexplosive = \"e\"\nlength = 1.0\n"
      "[delays]\n\"1\" = 0\n\"2\" = 0.02\n\"3\" = 0.03\n\"10\" = 0.1\n";
  const Case c = parse_case(text, "c.toml");
  ASSERT_EQ(c.delay_groups.size(), 4u);
  for (std::size_t k = 1; k < c.delay_groups.size(); ++k)
    EXPECT_LT(c.delay_groups[k - 1].name, c.delay_groups[k].name);
  const std::string resolved = resolved_case_toml(c);
  const Case back = parse_case(resolved, "case.resolved.toml");
  EXPECT_EQ(restart_signature(back), restart_signature(c));
  // an old signature, its [delays] lines in another order, reads as today's
  const std::string sig = restart_signature(c);
  const std::string sorted = "[delays]\n\"1\" = 0\n\"10\" = 0.10000000000000001\n\"2\" = 0.02\n\"3\" = 0.029999999999999999\n";
  ASSERT_NE(sig.find(sorted), std::string::npos) << sig;
  std::string old = sig;
  old.replace(old.find(sorted), sorted.size(),
              "[delays]\n\"2\" = 0.02\n\"3\" = 0.029999999999999999\n\"1\" = 0\n\"10\" = 0.10000000000000001\n");
  EXPECT_EQ(upgrade_signature(old), sig);
  // group names with a quote or a backslash: written escaped, sorted by the name itself
  std::string quoted = text;
  for (const auto& [from, to] : {std::pair<std::string, std::string>{R"(group = "2")", R"(group = "a\"")"},
                                 {R"(group = "3")", R"(group = "a$")"},
                                 {R"(group = "10")", R"(group = "a\\")"},
                                 {R"("2" = 0.02)", R"("a\"" = 0.02)"},
                                 {R"("3" = 0.03)", R"("a$" = 0.03)"},
                                 {R"("10" = 0.1)", R"("a\\" = 0.1)"}}) {
    const auto at = quoted.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    quoted.replace(at, from.size(), to);
  }
  const Case cq = parse_case(quoted, "c.toml");
  EXPECT_EQ(restart_signature(parse_case(resolved_case_toml(cq), "case.resolved.toml")), restart_signature(cq));
  EXPECT_EQ(upgrade_signature(restart_signature(cq)), restart_signature(cq));
}

}  // namespace
}  // namespace cdem
