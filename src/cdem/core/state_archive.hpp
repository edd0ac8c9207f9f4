// The state of a run as named records of plain bytes (checkpoints, io/checkpoint.hpp).
//
// A StateArchive is symmetric: the same `io(name, x)` calls save the state into records or
// load it back from them, so the list of what a checkpoint holds is written once per object
// (solver/run_state.cpp). Records hold plain bytes of trivially copyable values (arrays in
// global index order, so the format does not depend on the thread count, nor on a partition).
#pragma once
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace cdem {

// A checkpoint that cannot be read: missing, truncated, corrupted, or of another version.
class CheckpointError : public std::runtime_error {
 public:
  explicit CheckpointError(const std::string& what) : std::runtime_error(what) {}
};

struct StateRecord {
  std::uint32_t elem_size = 0;
  std::uint64_t count = 0;
  std::vector<unsigned char> bytes;
};

// A record name is an identifier of the program, never longer than this.
inline constexpr std::uint32_t kMaxRecordName = 256;

class StateArchive {
 public:
  // Saving: io() copies values into records. Loading: io() copies records into values.
  explicit StateArchive(bool loading) : loading_(loading) {}
  bool loading() const { return loading_; }

  template <class T>
  void io(const std::string& name, std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>, "checkpoint records hold plain bytes");
    if (!loading_) {
      StateRecord& r = put(name, sizeof(T), v.size());
      if (!v.empty()) std::memcpy(r.bytes.data(), v.data(), r.bytes.size());
      return;
    }
    const StateRecord& r = get(name, sizeof(T));
    v.resize(r.count);
    if (!v.empty()) std::memcpy(v.data(), r.bytes.data(), r.bytes.size());
  }
  template <class T>
  void io(const std::string& name, T& x) {
    static_assert(std::is_trivially_copyable_v<T>, "checkpoint records hold plain bytes");
    if (!loading_) {
      std::memcpy(put(name, sizeof(T), 1).bytes.data(), &x, sizeof(T));
      return;
    }
    const StateRecord& r = get(name, sizeof(T));
    if (r.count != 1) throw CheckpointError("record '" + name + "' holds an array, expected one value");
    std::memcpy(&x, r.bytes.data(), sizeof(T));
  }
  void io(const std::string& name, std::string& s);
  void io(const std::string& name, std::vector<std::string>& v);  // stored '\0'-separated

  bool has(const std::string& name) const { return records_.count(name) > 0; }
  const std::map<std::string, StateRecord>& records() const { return records_; }
  std::map<std::string, StateRecord>& records() { return records_; }

 private:
  StateRecord& put(const std::string& name, std::size_t elem_size, std::size_t count);
  const StateRecord& get(const std::string& name, std::size_t elem_size) const;
  bool loading_;
  std::map<std::string, StateRecord> records_;
};

}  // namespace cdem
