// Writes a run's outputs into its directory (SPEC 4):
//   case.resolved.toml   the case with every default filled in
//   fields.pvd + fields/fields_NNNN.vtu   blocks (own nodes): displacement, velocity, stress,
//                        pressure, von Mises, damage, damage mode, region, fragment id
//   cracks.pvd + cracks/cracks_NNNN.vtu   broken interface faces: mode, broken fraction,
//                        time of breaking, gas pressure on the faces
//   monitors.csv, energy.csv, fracture.csv   time histories (fracture.csv also per region:
//                        degree_area_<region>, with the model given to the constructor)
//   reactions.csv        reaction forces per constrained face set (write_reactions)
//   charges.csv          the charges' state (with_charges)
//   summary.json         key numbers of the run
// Every output carries the run's id (summary.json, the PVD files as a comment, the first line of
// case.resolved.toml), so that outputs of two runs can be told apart.
#pragma once
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cdem/analysis/damage.hpp"
#include "cdem/core/state_archive.hpp"
#include "cdem/io/case.hpp"
#include "cdem/io/vtu.hpp"
#include "cdem/model/model.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

class RunWriter {
 public:
  // With `m`, fracture.csv gets a degree_area_<region> column per region that has breakable
  // (rock) spring points (fracture_degree_by_region).
  // `resume`: a checkpoint's records (io_state): the histories are cut back to the rows they had
  // then and continued, the PVD series continues from its entries then. Else every file starts
  // anew. `charges_header` not empty: charges.csv is written (charges_csv()) with it.
  RunWriter(const std::string& dir, const Case& c, const Model* m = nullptr,
            const std::string& run_id = "", const std::string& charges_header = "",
            StateArchive* resume = nullptr);
  ~RunWriter();
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  // `max_up`: per node, the largest displacement along up so far (point array
  // max_up_displacement; UpliftTracker). `gas_pressure`: per interface, the charges' gas
  // pressure on its faces (Pa; crack cell array gas_pressure, 0 where none or when null).
  void write_fields(const Model& m, double t, const std::vector<double>* max_up = nullptr,
                    const std::vector<float>* gas_pressure = nullptr);
  // partition.vtu: the blocks in their reference place with the rank that steps each (cell
  // array `part`), written once by a distributed run (docs/parallel.md).
  void write_partition(const Model& m, const std::vector<std::int32_t>& part);
  // reactions.csv rows (time, face_set, fx, fy, fz), one per face set; the file is created at
  // the first call.
  void write_reactions(double t, const std::vector<std::string>& face_sets, const std::vector<Vec3>& force);
  // The regions of fracture.csv's per-region columns (region indices) and their column names.
  const std::vector<std::int32_t>& fracture_regions() const { return fracture_regions_; }
  // One history sample: energy.csv, fracture.csv (fd, and per region of fracture_regions() its
  // degree), monitors.csv (the monitor blocks' state in m).
  void write_history(const Model& m, double t, const EnergyBalance& e, const FractureDegree& fd,
                     const std::vector<double>& region_degree, const std::vector<std::int32_t>& monitor_blocks);
  void flush();
  // Flushes every history and throws std::runtime_error naming the file when a write failed
  // (a full disk): the run then stops with that message.
  void check_written();
  // Saves the writer's position: the byte size of each history (after a flush), the PVD
  // entries, the field output count.
  void io_state(StateArchive& ar);
  std::FILE* charges_csv() { return charges_; }
  const std::string& dir() const { return dir_; }
  int field_outputs() const { return frame_; }

 private:
  std::string dir_;
  const Case& case_;
  std::unique_ptr<PvdWriter> fields_pvd_, cracks_pvd_;
  std::FILE* monitors_ = nullptr;
  std::FILE* energy_ = nullptr;
  std::FILE* fracture_ = nullptr;
  std::FILE* reactions_ = nullptr;
  std::FILE* charges_ = nullptr;
  std::string run_id_;
  std::vector<std::int32_t> fracture_regions_;
  int frame_ = 0;
};

// Writes a JSON file from a flat list of (key, already-formatted JSON value) pairs.
void write_json(const std::string& path, const std::vector<std::pair<std::string, std::string>>& kv);
std::string json_string(const std::string& s);
std::string json_number(double x);
// A region name as a CSV column suffix: characters other than letters, digits, '_', '-' and '.'
// become '_' (degree_area_<region>).
std::string csv_column_name(const std::string& name);

}  // namespace cdem
