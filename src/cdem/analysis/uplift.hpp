// The maximum displacement along `analysis.up` (the vertical displacement of SPEC 5.3: fly-rock
// and heave), over time: per node (the VTU point array max_up_displacement) and per monitor
// (summary.json). Updated after every step (one pass over the nodes, parallel, no reduction:
// each node keeps its own maximum), so the peaks between outputs are not missed.
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/core/state_archive.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

// The up direction of a case: its analysis.up (`up`) normalised, else +y (2D) / +z (3D).
Vec3 up_direction(const Model& m, Vec3 up);

class UpliftTracker {
 public:
  // `up`: the unit up direction (up_direction); `monitors`: the number of monitor points.
  UpliftTracker(const Model& m, Vec3 up, std::size_t monitors);
  // After a step: max over time of (x - X) . up per node (starts at 0: the reference state).
  void update(const Model& m);
  const std::vector<double>& per_node() const { return max_up_; }
  // (the halo stage of a distributed run gathers the parts' maxima into the whole's)
  std::vector<double>& per_node() { return max_up_; }

  // The largest value over all nodes, and over the nodes of rock blocks only (explosive blocks
  // and blocks mostly filled by a bar charge left out, as the study does), with the reference
  // position of that node.
  struct Peak {
    double value = 0;
    Vec3 where{};
  };
  Peak peak(const Model& m, bool rock_only) const;

  // Per monitor (the block-mean displacement along up, as in monitors.csv), at each history
  // sample: the largest value and its time.
  void sample_monitors(const Model& m, const std::vector<std::int32_t>& monitor_blocks, double t);
  const std::vector<double>& monitor_max() const { return mon_max_; }
  const std::vector<double>& monitor_time() const { return mon_time_; }

  // Saves or loads the maxima so far (checkpoints).
  void io_state(StateArchive& ar) {
    ar.io("uplift.max_up", max_up_);
    ar.io("uplift.mon_max", mon_max_);
    ar.io("uplift.mon_time", mon_time_);
  }

 private:
  Vec3 up_;
  std::vector<double> max_up_;
  std::vector<double> mon_max_, mon_time_;
};

}  // namespace cdem
