// Writes a run's outputs into its directory (SPEC 4):
//   case.resolved.toml   the case with every default filled in
//   fields.pvd + fields/fields_NNNN.vtu   blocks (own nodes): displacement, velocity, stress,
//                        pressure, von Mises, damage, damage mode, region, fragment id
//   cracks.pvd + cracks/cracks_NNNN.vtu   broken interface faces: mode, broken fraction,
//                        time of breaking
//   monitors.csv, energy.csv, fracture.csv   time histories
//   summary.json         key numbers of the run
#pragma once
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cdem/io/case.hpp"
#include "cdem/io/vtu.hpp"
#include "cdem/model/model.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

class RunWriter {
 public:
  RunWriter(const std::string& dir, const Case& c);
  ~RunWriter();
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  void write_fields(const Model& m, double t);
  void write_history(const Model& m, double t, const EnergyBalance& e,
                     const std::vector<std::int32_t>& monitor_blocks);
  void flush();
  const std::string& dir() const { return dir_; }
  int field_outputs() const { return frame_; }

 private:
  std::string dir_;
  const Case& case_;
  std::unique_ptr<PvdWriter> fields_pvd_, cracks_pvd_;
  std::FILE* monitors_ = nullptr;
  std::FILE* energy_ = nullptr;
  std::FILE* fracture_ = nullptr;
  int frame_ = 0;
};

// Writes a JSON file from a flat list of (key, already-formatted JSON value) pairs.
void write_json(const std::string& path, const std::vector<std::pair<std::string, std::string>>& kv);
std::string json_string(const std::string& s);
std::string json_number(double x);

}  // namespace cdem
