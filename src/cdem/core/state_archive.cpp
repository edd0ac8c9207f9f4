#include "cdem/core/state_archive.hpp"

#include <fmt/format.h>

namespace cdem {

void StateArchive::io(const std::string& name, std::string& s) {
  std::vector<char> v(s.begin(), s.end());
  io(name, v);
  if (loading_) s.assign(v.begin(), v.end());
}

void StateArchive::io(const std::string& name, std::vector<std::string>& v) {
  std::vector<char> all;
  if (!loading_)
    for (const auto& s : v) all.insert(all.end(), s.c_str(), s.c_str() + s.size() + 1);
  io(name, all);
  if (!loading_) return;
  v.clear();
  std::string cur;
  for (char ch : all) {
    if (ch == '\0') {
      v.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
}

StateRecord& StateArchive::put(const std::string& name, std::size_t elem_size, std::size_t count) {
  if (name.empty() || name.size() > kMaxRecordName || records_.count(name))
    throw std::logic_error("checkpoint record '" + name + "': empty, too long or written twice");
  StateRecord& r = records_[name];
  r.elem_size = static_cast<std::uint32_t>(elem_size);
  r.count = count;
  r.bytes.resize(elem_size * count);
  return r;
}

const StateRecord& StateArchive::get(const std::string& name, std::size_t elem_size) const {
  const auto it = records_.find(name);
  if (it == records_.end())
    throw CheckpointError(fmt::format("the checkpoint has no record '{}' (written by another version "
                                      "of cdemblast, or for another kind of model)",
                                      name));
  if (it->second.elem_size != elem_size)
    throw CheckpointError(fmt::format("checkpoint record '{}' holds elements of {} bytes, expected {}",
                                      name, it->second.elem_size, elem_size));
  return it->second;
}

}  // namespace cdem
