#include "cdem/io/toml_reader.hpp"

#include <fmt/format.h>

#include <cmath>

#include "cdem/core/error.hpp"
#include "cdem/core/text.hpp"

namespace cdem {
namespace {
std::string type_name(const toml::value& v) {
  switch (v.type()) {
    case toml::value_t::boolean:
      return "a boolean";
    case toml::value_t::integer:
      return "an integer";
    case toml::value_t::floating:
      return "a number";
    case toml::value_t::string:
      return "a string";
    case toml::value_t::array:
      return "an array";
    case toml::value_t::table:
      return "a table";
    default:
      return "a date or time";
  }
}
}  // namespace

TomlTable::TomlTable(const toml::value& v, std::string file, std::string path)
    : v_(&v), file_(std::move(file)), path_(std::move(path)) {}

std::string TomlTable::where(const std::string& key) const {
  return fmt::format("{}: key '{}{}'", file_, path_.empty() ? "" : path_ + ".", key);
}

void TomlTable::fail(const std::string& key, const std::string& expected) const {
  const toml::value* r = raw(key);
  if (r)
    throw InputError(fmt::format("{}: expected {}, got {}", where(key), expected, type_name(*r)));
  throw InputError(fmt::format("{}: missing; expected {}", where(key), expected));
}

const toml::value* TomlTable::raw(const std::string& key) const {
  if (!v_->is_table()) return nullptr;
  const auto& t = v_->as_table();
  auto it = t.find(key);
  return it == t.end() ? nullptr : &it->second;
}

bool TomlTable::has(const std::string& key) const { return raw(key) != nullptr; }

double TomlTable::number(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r) fail(key, "a number");
  double x;
  if (r->is_floating())
    x = r->as_floating();
  else if (r->is_integer())
    x = static_cast<double>(r->as_integer());
  else
    fail(key, "a number");
  if (!std::isfinite(x))
    throw InputError(fmt::format("{}: expected a finite number, got {}", where(key), x));
  return x;
}
double TomlTable::number(const std::string& key, double dflt) const {
  return has(key) ? number(key) : dflt;
}
double TomlTable::positive(const std::string& key) const {
  const double x = number(key);
  if (!(x > 0))
    throw InputError(fmt::format("{}: expected a positive number, got {}", where(key), x));
  return x;
}
double TomlTable::positive(const std::string& key, double dflt) const {
  return has(key) ? positive(key) : dflt;
}
double TomlTable::non_negative(const std::string& key, double dflt) const {
  const double x = number(key, dflt);
  if (x < 0) throw InputError(fmt::format("{}: expected a number >= 0, got {}", where(key), x));
  return x;
}
std::int64_t TomlTable::integer(const std::string& key, std::int64_t dflt) const {
  const toml::value* r = raw(key);
  if (!r) return dflt;
  if (!r->is_integer()) fail(key, "an integer");
  return r->as_integer();
}
bool TomlTable::boolean(const std::string& key, bool dflt) const {
  const toml::value* r = raw(key);
  if (!r) return dflt;
  if (!r->is_boolean()) fail(key, "true or false");
  return r->as_boolean();
}
std::string TomlTable::string(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r || !r->is_string()) fail(key, "a string");
  const std::string& s = r->as_string().str;
  // Escapes can put any character in a TOML string; names and paths need no control characters
  // (they go into messages, CSV and VTU files).
  if (const auto bad = check_text(s, false))
    throw InputError(
        fmt::format("{}: the string holds {} at byte {}", where(key), bad->what, bad->offset + 1));
  return s;
}
std::string TomlTable::string(const std::string& key, const std::string& dflt) const {
  return has(key) ? string(key) : dflt;
}
std::string TomlTable::choice(const std::string& key, const std::vector<std::string>& allowed,
                              const std::string& dflt) const {
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "'" : ", '") + a + "'";
  if (!has(key) && dflt.empty()) fail(key, "one of " + list);
  const std::string s = has(key) ? string(key) : dflt;
  for (const auto& a : allowed)
    if (a == s) return s;
  throw InputError(fmt::format("{}: '{}' is not one of {}", where(key), s, list));
}
std::vector<double> TomlTable::numbers(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r || !r->is_array()) fail(key, "an array of numbers");
  std::vector<double> out;
  for (const auto& e : r->as_array()) {
    if (e.is_floating())
      out.push_back(e.as_floating());
    else if (e.is_integer())
      out.push_back(static_cast<double>(e.as_integer()));
    else
      throw InputError(fmt::format("{}: expected an array of numbers, found {} in it", where(key),
                                   type_name(e)));
    if (!std::isfinite(out.back()))
      throw InputError(fmt::format("{}: entry {} is {}; expected finite numbers", where(key),
                                   out.size() - 1, out.back()));
  }
  return out;
}
std::vector<std::string> TomlTable::strings(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r || !r->is_array()) fail(key, "an array of strings");
  std::vector<std::string> out;
  for (const auto& e : r->as_array()) {
    if (!e.is_string())
      throw InputError(fmt::format("{}: expected an array of strings, found {} in it", where(key),
                                   type_name(e)));
    if (const auto bad = check_text(e.as_string().str, false))
      throw InputError(fmt::format("{}: entry {} holds {}", where(key), out.size(), bad->what));
    out.push_back(e.as_string().str);
  }
  return out;
}
Vec3 TomlTable::vec(const std::string& key) const {
  const auto a = numbers(key);
  if (a.size() != 2 && a.size() != 3)
    throw InputError(
        fmt::format("{}: expected 2 or 3 numbers [x, y(, z)], got {}", where(key), a.size()));
  return {a[0], a[1], a.size() == 3 ? a[2] : 0.0};
}
Vec3 TomlTable::vec(const std::string& key, Vec3 dflt) const { return has(key) ? vec(key) : dflt; }

std::vector<std::pair<double, double>> TomlTable::table(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r || !r->is_array()) fail(key, "an array of [time, value] pairs");
  std::vector<std::pair<double, double>> out;
  for (const auto& e : r->as_array()) {
    if (!e.is_array() || e.as_array().size() != 2)
      throw InputError(fmt::format("{}: expected an array of [time, value] pairs", where(key)));
    double p[2];
    for (int i = 0; i < 2; ++i) {
      const auto& q = e.as_array()[i];
      if (q.is_floating())
        p[i] = q.as_floating();
      else if (q.is_integer())
        p[i] = static_cast<double>(q.as_integer());
      else
        throw InputError(fmt::format("{}: expected numbers in [time, value]", where(key)));
      if (!std::isfinite(p[i]))
        throw InputError(fmt::format("{}: entry {} has {} {}; expected finite numbers", where(key),
                                     out.size(), i == 0 ? "time" : "value", p[i]));
    }
    if (!out.empty() && p[0] <= out.back().first)
      throw InputError(fmt::format("{}: times must increase (found {} after {})", where(key), p[0],
                                   out.back().first));
    out.emplace_back(p[0], p[1]);
  }
  if (out.empty()) throw InputError(fmt::format("{}: the table is empty", where(key)));
  return out;
}

std::optional<TomlTable> TomlTable::sub(const std::string& key) const {
  const toml::value* r = raw(key);
  if (!r) return std::nullopt;
  if (!r->is_table()) fail(key, "a table");
  return TomlTable(*r, file_, path_.empty() ? key : path_ + "." + key);
}

std::vector<TomlTable> TomlTable::array_of_tables(const std::string& key) const {
  std::vector<TomlTable> out;
  const toml::value* r = raw(key);
  if (!r) return out;
  if (r->is_table()) {
    out.emplace_back(*r, file_, (path_.empty() ? key : path_ + "." + key));
    return out;
  }
  if (!r->is_array()) fail(key, fmt::format("an array of tables ([[{}]])", key));
  std::size_t i = 0;
  for (const auto& e : r->as_array()) {
    if (!e.is_table())
      throw InputError(fmt::format("{}: expected an array of tables ([[{}]])", where(key), key));
    out.emplace_back(e, file_, fmt::format("{}{}[{}]", path_.empty() ? "" : path_ + ".", key, i++));
  }
  return out;
}

void TomlTable::check_known(const std::vector<std::string>& known) const {
  if (!v_->is_table()) return;
  for (const auto& [k, val] : v_->as_table()) {
    bool ok = false;
    for (const auto& n : known) ok = ok || n == k;
    if (!ok) {
      std::string list;
      for (const auto& n : known) list += (list.empty() ? "" : ", ") + n;
      throw InputError(fmt::format("{}: unknown key (known keys here: {})", where(k), list));
    }
  }
}

}  // namespace cdem
