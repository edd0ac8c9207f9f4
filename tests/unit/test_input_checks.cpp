// Checks of untrusted input before the parsers and the mesher see it: text (UTF-8, control
// characters, nesting), case values (NaN, ranges, --set indices), the element estimate of a
// generated mesh and the run-size caps.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <string>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/core/text.hpp"
#include "cdem/io/case.hpp"
#include "cdem/io/case_text.hpp"
#include "cdem/io/run_limits.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/mesh_estimate.hpp"

namespace cdem {
namespace {

std::string problem(std::string_view s, bool multiline = true) {
  const auto p = check_text(s, multiline);
  return p ? p->what + " @" + std::to_string(p->offset) : "";
}

TEST(Text, Utf8Validation) {
  EXPECT_EQ(problem("plain ASCII\twith tab\r\n"), "");
  EXPECT_EQ(problem("\xc3\xa9 \xe2\x82\xac \xf0\x9f\x92\xa5 \xf4\x8f\xbf\xbf"),
            "");  // é € 💥 U+10FFFF
  EXPECT_EQ(problem("a\xff"), "invalid UTF-8 (byte 0xff) @1");
  EXPECT_EQ(problem("\xc0\x80"), "invalid UTF-8 (byte 0xc0) @0");  // overlong NUL
  EXPECT_EQ(problem("\xe0\x80\xaf"), "invalid UTF-8 (an overlong form) @0");
  EXPECT_EQ(problem("\xed\xa0\x80"), "invalid UTF-8 (a surrogate) @0");
  EXPECT_EQ(problem("\xf4\x90\x80\x80"), "invalid UTF-8 (beyond U+10FFFF) @0");
  EXPECT_EQ(problem("ab\xe2\x82"), "invalid UTF-8 (a sequence cut short at the end) @2");
  EXPECT_EQ(problem("\xe2\x28\xa1"), "invalid UTF-8 (byte 0x28 after 0xe2) @0");
  EXPECT_EQ(problem(std::string_view("a\0b", 3)), "a NUL byte @1");
  EXPECT_EQ(problem("bell\x07"), "control character U+0007 @4");
  EXPECT_EQ(problem("\x7f"), "control character U+007F @0");
  EXPECT_EQ(problem("\xc2\x85"), "control character U+0085 @0");
  EXPECT_EQ(problem("two\nlines", false), "control character U+000A @3");
  EXPECT_EQ(printable("a\x01\xff\\b"), "a\\x01\\xff\\x5cb");
}

std::string case_error(std::string_view text, const std::vector<std::string>& overrides = {}) {
  try {
    (void)parse_case(text, "c.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The smallest valid case: a generated square.
const std::string kCase =
    "[mesh.generate]\nshape = \"rectangle\"\nsize = [1.0, 1.0]\nelement_size = 0.25\n"
    "[simulation]\nend_time = 1e-3\n"
    "[[material]]\nname = \"r\"\nregions = [\"rock\"]\ndensity = 2600\nyoungs_modulus = 3e10\n"
    "poisson_ratio = 0.25\n";

TEST(CaseText, RefusedBeforeToml) {
  EXPECT_EQ(case_error(kCase), "");
  // toml11 3.7.1 reads past its buffer on this 9-byte file (a literal key with invalid UTF-8).
  EXPECT_EQ(case_error("'ab\xff' = 1"),
            "c.toml: line 1, column 4: invalid UTF-8 (byte 0xff) (a "
            "case file is UTF-8 text)");
  EXPECT_NE(case_error(std::string("title = \"x\0y\"\n", 14) + kCase).find("a NUL byte"),
            std::string::npos);
  EXPECT_NE(case_error(std::string(5 << 20, '#')).find("more than the"), std::string::npos);
  // Nesting: toml11 recurses once per level.
  const std::string deep = "a = " + std::string(100000, '[') + std::string(100000, ']') + "\n";
  EXPECT_NE(case_error(deep).find("line 1, column 21: arrays or inline tables nested more than 16"),
            std::string::npos);
  std::string tables = "a = ";
  for (int i = 0; i < 20; ++i) tables += "{b = ";
  EXPECT_NE(case_error(tables + "1" + std::string(20, '}')).find("nested more than 16"),
            std::string::npos);
  // Dotted keys: a key, a table header, a key inside an inline table (one level each in toml11).
  std::string dotted = "a";
  for (int i = 0; i < 70; ++i) dotted += ".a";
  for (const std::string& text : {dotted + " = 1", "[" + dotted + "]", "x = {" + dotted + " = 1}"})
    EXPECT_NE(case_error(text).find("a dotted key of more than 64 parts"), std::string::npos)
        << text;
  EXPECT_NE(case_error(kCase, {dotted + "=1"}).find("a key path of more than 64 parts"),
            std::string::npos);
  // Dots in values are not key parts.
  EXPECT_EQ(case_error("title = \"a.b\"\n" + kCase + "damping = 0." + std::string(80, '0') + "\n"),
            "");
  // Brackets in strings and comments do not count.
  EXPECT_EQ(case_error("title = \"" + std::string(40, '[') + "\" # " + std::string(40, '{') + "\n" +
                       kCase),
            "");
  EXPECT_EQ(case_error("title = '''" + std::string(40, '[') + "'''\n" + kCase), "");
}

// A dotted key of 100 000 parts overflowed the stack in toml11 (found while writing these
// tests; kept in tests/fuzz/regressions/case too): refused before toml11 sees it.
// toml11 overflows a signed integer on a binary integer of 63 digits or more (found by fuzzing:
// tests/fuzz/regressions/case/toml11_binary_integer_overflow.toml): refused before it parses.
TEST(CaseText, LongBinaryIntegerIsRefusedBeforeToml) {
  const std::string ones(70, '1');
  EXPECT_NE(case_error("a = 0b" + ones + "\n").find("line 1, column 5: a binary integer of more than 62 digits"),
            std::string::npos);
  EXPECT_NE(case_error("a = [1, 0b" + std::string(63, '0') + "]\n").find("binary integer of more than 62"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"simulation.gravity=[0b" + ones + ", 0, 0]"}).find("binary integer"),
            std::string::npos);
  // 62 digits (underscores not counted), keys and strings that look alike pass the scan
  const std::string d62 = "0b1_" + std::string(61, '0');
  EXPECT_EQ(case_error("title = \"0b" + ones + "\"\n0b" + ones + " = 1\n" + kCase).find("binary integer"),
            std::string::npos);
  EXPECT_EQ(case_error("a = " + d62 + "\n").find("binary integer"), std::string::npos);
}

TEST(CaseText, HugeDottedKeyIsRefusedBeforeToml) {
  std::string dotted;
  for (int i = 0; i < 100000; ++i) dotted += i ? ".a" : "a";
  EXPECT_NE(case_error(dotted + " = 1\n").find("line 1, column 128: a dotted key of more than 64"),
            std::string::npos);
}

TEST(CaseValues, NanAnywhereAndNamedKeys) {
  EXPECT_NE(case_error(kCase, {"simulation.gravity=[0.0, nan]"})
                .find("key 'simulation.gravity': entry 1 is nan"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"simulation.output_times=[inf]"})
                .find("key 'simulation.output_times': entry 0 is inf"),
            std::string::npos);
  EXPECT_NE(
      case_error(kCase, {"simulation.end_time=nan"}).find("expected a finite number, got nan"),
      std::string::npos);
  EXPECT_NE(case_error(kCase, {"material.-1.density=5"}).find("'-1' is not an index"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"material.99999999999999999999.density=5"}).find("is not an index"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"title=\"a\\nb\""}).find("control character U+000A"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {std::string("title=\"a\x01\"")}).find("control character U+0001"),
            std::string::npos);
}

TEST(CaseValues, PhysicalRanges) {
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::off);
  EXPECT_NE(case_error(kCase, {"material.0.youngs_modulus=1e308"})
                .find("key 'material[0].youngs_modulus': 1e+308 Pa is no Young's modulus"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"material.0.density=1e-300"})
                .find("key 'material[0].density': 1e-300 kg/m^3 is no density"),
            std::string::npos);
  EXPECT_EQ(case_error(kCase, {"material.0.density=2.6"}), "");  // g/cm^3? a warning only
  EXPECT_NE(case_error(kCase, {"simulation.threads=100000"}).find("to 4096, got 100000"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"simulation.gravity=[0, -1e6]"}).find("1000 times the Earth's"),
            std::string::npos);
  EXPECT_NE(case_error(kCase, {"mesh.generate.hole=[{center=[0.5, 0.5, 0.2], radius=0.1}]"})
                .find("key 'mesh.generate.hole[0].center': z = 0.2 for a rectangle"),
            std::string::npos);
  spdlog::set_level(level);
}

TEST(CaseValues, MonitorCap) {
  std::string many = kCase;
  for (int i = 0; i <= 10000; ++i)
    many += "[[monitor]]\nname = \"m" + std::to_string(i) + "\"\npoint = [0.5, 0.5]\n";
  EXPECT_NE(case_error(many).find("10001 [[monitor]] entries, more than the 10000 allowed"),
            std::string::npos);
  EXPECT_EQ(case_error(many, {"simulation.allow_large_run=true"}), "");
}

TEST(CaseValues, CoincidentHoles) {
  const std::string hole =
      "[[hole]]\nname = \"%\"\ncollar = [0.5, 1.0]\nend = [0.5, 0.5]\ndiameter = 0.05\n"
      "[[hole.charge]]\nexplosive = \"emulsion\"\nlength = 0.2\n";
  auto named = [&](const std::string& n, const std::string& ends) {
    std::string h = hole;
    h.replace(h.find('%'), 1, n);
    if (!ends.empty()) h.replace(h.find("collar"), h.find("diameter") - h.find("collar"), ends);
    return h;
  };
  // The same hole twice, or drilled from the other end: refused; a hole beside it: accepted.
  EXPECT_NE(case_error(kCase + named("a", "") + named("b", "")).find("hole 'b' lies on hole 'a'"),
            std::string::npos);
  EXPECT_NE(
      case_error(kCase + named("a", "") + named("b", "collar = [0.5, 0.5]\nend = [0.5, 1.0]\n"))
          .find("lies on hole 'a'"),
      std::string::npos);
  EXPECT_EQ(
      case_error(kCase + named("a", "") + named("b", "collar = [0.7, 1.0]\nend = [0.7, 0.5]\n")),
      "");
}

TEST(RunLimits, FieldOutputsAndSteps) {
  Case c = parse_case(kCase, "c.toml");
  c.output_interval = 1e-15;
  EXPECT_THROW(check_field_outputs(c), InputError);
  c.allow_large_run = true;
  EXPECT_THROW(check_field_outputs(c), InputError);  // 1e12 outputs: beyond the hard limit too
  c.output_interval = 1e-9;                          // 1e6 + 2 outputs
  EXPECT_THROW(check_field_outputs(c), InputError);
  c.output_interval = 1e-8;
  EXPECT_NO_THROW(check_field_outputs(c));
  c.allow_large_run = false;
  c.output_interval = 0;
  // Steps: 1e-3 s at 1e-12 s is 1e9 steps (over the cap unless allowed); at 1e-30 s 1e27 steps
  // overflow whatever the case says, unless max_steps bounds the run.
  EXPECT_THROW(check_run_size(c, 1e-12, "test"), InputError);
  c.allow_large_run = true;
  c.history_interval = 1e-3;
  EXPECT_DOUBLE_EQ(check_run_size(c, 1e-12, "test").steps, 1e9);
  EXPECT_THROW(check_run_size(c, 1e-30, "test"), InputError);
  c.max_steps = 1000;
  EXPECT_DOUBLE_EQ(check_run_size(c, 1e-30, "test").steps, 1000);
  // History samples: every step (history_interval = 0) of a long run is capped.
  c.max_steps = 0;
  c.allow_large_run = false;
  c.history_interval = 0;
  EXPECT_THROW(check_run_size(c, 1e-11, "test"), InputError);  // 1e8 steps and samples
}

// The estimate is an upper bound of what Gmsh makes, within a few times it (rectangle with a
// refinement and a hole, box).
TEST(MeshEstimate, BoundsTheGeneratedElementCount) {
  GenerateSpec a;
  a.shape = "rectangle";
  a.size = {2, 1, 0};
  a.element_size = 0.05;
  a.refine = {RefineSpec{{0.5, 0.5, 0}, 0.005, 0.05}};
  a.holes = {HoleSpec{{1.5, 0.5, 0}, 0.02, {0, 0, 1}, 0, ""}};
  GenerateSpec b;
  b.shape = "box";
  b.size = {1, 0.5, 0.5};
  b.element_size = 0.1;
  for (const GenerateSpec& s : {a, b}) {
    const double actual = static_cast<double>(generate_mesh(s).num_elements());
    const MeshEstimate e = estimate_generated_mesh(s);
    EXPECT_GE(e.elements, actual) << s.shape;
    EXPECT_LE(e.elements, 4 * actual) << s.shape;
  }
  a.refine[0].size = 1e-7;
  const MeshEstimate e = estimate_generated_mesh(a);
  EXPECT_EQ(e.largest_key, "refine[0].size");
  EXPECT_NE(model_size_problem(e.elements, 2, "").find("more than the 1e+08"), std::string::npos);
}

}  // namespace
}  // namespace cdem
