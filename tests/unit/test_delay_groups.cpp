// Delay groups (issue 14 item 2): holes name a group, [delays] sets a delay per group (one for
// every deck, or one per deck from the bottom up) that adds to each deck's own delay, and one
// --set delays.<group>=... retimes a whole group. The ignition times of the bar segments are
// checked against t_D0 + d_j / D (SPEC 2, eq. 12).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/io/case.hpp"
#include "cdem/solver/run.hpp"

namespace cdem {
namespace {

namespace fs = std::filesystem;

// A 1 m box with four vertical bar holes: "cut" (group 1, two decks), "east" (group 2, own
// delay 1 ms), "west" (group 3), "lone" (no group, own delay 5 ms).
const char* kCase = R"(
title = "delay_groups"
[mesh.generate]
shape = "box"
size = [1.0, 1.0, 1.0]
element_size = 0.25
[simulation]
end_time = 0.05
[[material]]
name = "granite"
regions = ["rock"]
density = 2681
youngs_modulus = 99.3e9
poisson_ratio = 0.28
[[interface]]
name = "bond"
law = "elastic"
[[hole]]
name = "cut"
group = "1"
collar = [0.3, 0.3, 1.0]
end = [0.3, 0.3, 0.2]
diameter = 0.02
[[hole.charge]]
explosive = "rdx"
length = 0.3
[[hole.charge]]
stemming = 0.1
[[hole.charge]]
explosive = "rdx"
length = 0.2
[[hole]]
name = "east"
group = "2"
collar = [0.7, 0.3, 1.0]
end = [0.7, 0.3, 0.4]
diameter = 0.02
[[hole.charge]]
explosive = "rdx"
length = 0.3
delay = 0.001
[[hole]]
name = "west"
group = "3"
collar = [0.3, 0.7, 1.0]
end = [0.3, 0.7, 0.4]
diameter = 0.02
[[hole.charge]]
explosive = "rdx"
length = 0.3
[[hole]]
name = "lone"
collar = [0.7, 0.7, 1.0]
end = [0.7, 0.7, 0.4]
diameter = 0.02
[[hole.charge]]
explosive = "rdx"
length = 0.3
delay = 0.005
[delays]
"1" = [0.01, 0.0]
"2" = 0.02
"3" = 0.03
)";

class DelayGroups : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("cdem_delay_groups_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "case.toml").string();
    std::ofstream(path_) << kCase;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
  std::string path_;
};

double deck_delay(const Case& c, const std::string& hole, std::size_t deck) {
  for (const auto& h : c.holes)
    if (h.name == hole) return h.decks.at(deck).delay;
  ADD_FAILURE() << "no hole " << hole;
  return -1;
}

// Every segment of every bar ignites at the deck's t_D0 + d_j / D (d_j: its centre's distance
// from the initiation point).
void expect_ignition(const Case& c, const std::map<std::pair<std::string, int>, double>& t0) {
  const Mesh mesh = load_mesh(c);
  const Model m = build_case_model(c, mesh);
  const BarCharges bc = build_bar_charges(m, charge_spec(c));
  const double D = 8350;  // the built-in rdx (SPEC 5.3)
  ASSERT_EQ(bc.bars.size(), t0.size());
  for (const auto& b : bc.bars) {
    const auto it = t0.find({b.hole, b.deck});
    ASSERT_NE(it, t0.end()) << b.hole << " deck " << b.deck;
    for (auto j = b.seg_begin; j < b.seg_end; ++j) {
      const double dj = (j - b.seg_begin + 0.5) * b.h;
      EXPECT_NEAR(bc.seg_t_ign[j], it->second + dj / D, 1e-15)
          << b.hole << " deck " << b.deck << " segment " << j;
    }
  }
}

TEST_F(DelayGroups, IgnitionTimesAreTheGroupDelayPlusTheDecksOwn) {
  const Case c = load_case(path_);
  EXPECT_DOUBLE_EQ(deck_delay(c, "cut", 0), 0.01);  // the lower deck
  EXPECT_DOUBLE_EQ(deck_delay(c, "cut", 1), 0.0);   // the upper deck
  EXPECT_DOUBLE_EQ(deck_delay(c, "east", 0), 0.021);
  EXPECT_DOUBLE_EQ(deck_delay(c, "west", 0), 0.03);
  EXPECT_DOUBLE_EQ(deck_delay(c, "lone", 0), 0.005);
  expect_ignition(c, {{{"cut", 0}, 0.01}, {{"cut", 1}, 0.0}, {{"east", 0}, 0.021},
                      {{"west", 0}, 0.03}, {{"lone", 0}, 0.005}});
}

TEST_F(DelayGroups, OneSetRetimesAGroup) {
  // Scheme A of SPEC 5.3: everything at 0 (each group one override; "1" as one number now).
  const Case a = load_case(path_, {"delays.1=0.0", "delays.2=0", "delays.3=0.0"});
  expect_ignition(a, {{{"cut", 0}, 0.0}, {{"cut", 1}, 0.0}, {{"east", 0}, 0.001},
                      {{"west", 0}, 0.0}, {{"lone", 0}, 0.005}});
  // One deck of a per-deck entry, by index.
  const Case b = load_case(path_, {"delays.1.1=0.004", "delays.2=0.025"});
  EXPECT_DOUBLE_EQ(deck_delay(b, "cut", 0), 0.01);
  EXPECT_DOUBLE_EQ(deck_delay(b, "cut", 1), 0.004);
  EXPECT_DOUBLE_EQ(deck_delay(b, "east", 0), 0.026);
  // A group's delay given for the first time on the command line.
  const std::string no_table = std::string(kCase).substr(0, std::string(kCase).find("[delays]"));
  const Case c = load_case(write("no_table.toml", no_table), {"delays.3=0.002"});
  EXPECT_DOUBLE_EQ(deck_delay(c, "west", 0), 0.002);
  EXPECT_DOUBLE_EQ(deck_delay(c, "east", 0), 0.001);
  EXPECT_DOUBLE_EQ(deck_delay(c, "cut", 0), 0.0);
}

TEST_F(DelayGroups, ResolvedCaseKeepsGroupsAndOwnDelays) {
  const Case c = load_case(path_, {"delays.2=0.025"});
  const std::string resolved = write("resolved.toml", resolved_case_toml(c));
  const Case r = load_case(resolved);
  for (const auto& h : c.holes)
    for (std::size_t k = 0; k < h.decks.size(); ++k)
      EXPECT_DOUBLE_EQ(deck_delay(r, h.name, k), h.decks[k].delay) << h.name << " deck " << k;
  EXPECT_NE(resolved_case_toml(r).find("\"2\" = 0.025"), std::string::npos);
}

std::string error_of(const std::string& path, const std::vector<std::string>& sets) {
  try {
    load_case(path, sets);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST_F(DelayGroups, MistakesAreInputErrorsNamingTheKey) {
  std::string e = error_of(path_, {"delays.4=0.01"});
  EXPECT_NE(e.find("key 'delays.4'"), std::string::npos) << e;
  EXPECT_NE(e.find("no [[hole]] has group = \"4\""), std::string::npos) << e;
  e = error_of(path_, {"delays.2=[0.01, 0.02]"});
  EXPECT_NE(e.find("key 'delays.2'"), std::string::npos) << e;
  EXPECT_NE(e.find("hole 'east' of group '2' has 1 deck(s)"), std::string::npos) << e;
  e = error_of(path_, {"delays.3=-0.01"});
  EXPECT_NE(e.find(">= 0"), std::string::npos) << e;
  e = error_of(path_, {"delays.3=\"late\""});
  EXPECT_NE(e.find("key 'delays.3'"), std::string::npos) << e;
  e = error_of(path_, {"hole.0.group=\"a.b\""});
  EXPECT_NE(e.find("cannot contain '.'"), std::string::npos) << e;
}

}  // namespace
}  // namespace cdem
