// Typed, path-tracking access to a TOML table: every error names the file, the dotted key and
// what was expected; unknown keys (typos) are errors too.
#pragma once
#include <toml.hpp>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

class TomlTable {
 public:
  TomlTable(const toml::value& v, std::string file, std::string path);

  bool has(const std::string& key) const;
  double number(const std::string& key) const;  // required
  double number(const std::string& key, double dflt) const;
  double positive(const std::string& key) const;                 // required, > 0
  double positive(const std::string& key, double dflt) const;    // > 0
  double non_negative(const std::string& key, double dflt) const;  // >= 0
  std::int64_t integer(const std::string& key, std::int64_t dflt) const;
  bool boolean(const std::string& key, bool dflt) const;
  std::string string(const std::string& key) const;
  std::string string(const std::string& key, const std::string& dflt) const;
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string& dflt) const;
  std::vector<double> numbers(const std::string& key) const;
  std::vector<std::string> strings(const std::string& key) const;
  // A point or vector of 2 (z = 0) or 3 numbers.
  Vec3 vec(const std::string& key) const;
  Vec3 vec(const std::string& key, Vec3 dflt) const;
  std::vector<std::pair<double, double>> table(const std::string& key) const;  // [[t, v], ...]
  std::optional<TomlTable> sub(const std::string& key) const;       // a sub-table
  std::vector<TomlTable> array_of_tables(const std::string& key) const;
  const toml::value* raw(const std::string& key) const;

  // Throws if the table holds a key not listed (catches typos such as 'end_tme').
  void check_known(const std::vector<std::string>& known) const;

  [[noreturn]] void fail(const std::string& key, const std::string& expected) const;
  std::string where(const std::string& key) const;
  const std::string& file() const { return file_; }

 private:
  const toml::value* v_;
  std::string file_, path_;
};

}  // namespace cdem
