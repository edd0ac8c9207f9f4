// The record of the extra loads of a step (the explosive models', through the step's load hooks),
// for their work (solver/simulation.hpp, the energy balance).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// Forces applied by extra loads during a step, kept so that their work can be integrated with
// the mid-step velocity: W += F(n) . (v(n-1/2) + v(n+1/2)) / 2 dt. The half with v(n-1/2) is
// summed as the loads are added (power_old); the step adds the half with v(n+1/2).
struct AppliedLoads {
  std::vector<std::int32_t> node;  // single loads: f on node
  std::vector<Vec3> force;
  std::vector<std::int32_t> pair_b, pair_a;  // pair loads: f on pair_b, -f on pair_a
  std::vector<Vec3> pair_force;
  double power_old = 0;  // sum of f . v(n-1/2) over the loads added this step
  void clear() {
    node.clear();
    force.clear();
    pair_b.clear();
    pair_a.clear();
    pair_force.clear();
    power_old = 0;
    owned.clear();
  }
  // Adds f to node n of the model and records it.
  void add(Model& m, std::int32_t n, Vec3 f) {
    m.f[n] += f;
    node.push_back(n);
    force.push_back(f);
    power_old += dot(f, m.v[n]);
  }
  // Pair loads (a pressure pushing two faces apart: f on pair_b, -f on pair_a, recorded once):
  // room for n more, filled in parallel (pair_b, pair_a, pair_force from the returned index
  // on); the caller adds their forces and books their power (book_pair_power). The record grows
  // only beyond its capacity.
  std::size_t append_pairs(std::size_t n) {
    const std::size_t first = pair_b.size();
    pair_b.resize(first + n);
    pair_a.resize(first + n);
    pair_force.resize(first + n);
    return first;
  }
  // Books the pair loads' power terms power[0, n) into power_old, in record order. The caller
  // adds their forces itself, each node's in record order (update_gas: per block, in parallel).
  void book_pair_power(std::size_t n, const double* power) {
    for (std::size_t i = 0; i < n; ++i) power_old += power[i];
  }
  // sum of f . v over the loads, with the model's velocities now (after the integration: v(n+1/2))
  double power_now(const Model& m);
  std::vector<double> terms;  // power_now's per-load terms (grown once)

  // A part of a distributed run (the halo stage, solver/halo_charges.hpp) does not record its
  // loads above: its step's load power is summed over the whole model's record, in that record's
  // order (single loads, then pair loads, as power_now; power_old adds the pair loads first, as
  // a one-process step books them first). It lists here the loads it owns: each one's place in
  // the whole record, its nodes (a < 0: a single load on b), its force and its term with
  // v(n-1/2); and the whole record's counts.
  struct Owned {
    std::vector<std::int64_t> at;
    std::vector<std::int32_t> b, a;
    std::vector<Vec3> f;
    std::vector<double> old;
    std::int64_t whole_single = 0, whole_pairs = 0;
    void clear() {
      at.clear(), b.clear(), a.clear(), f.clear(), old.clear();
      whole_single = whole_pairs = 0;
    }
    void add(std::int64_t place, std::int32_t nb, std::int32_t na, Vec3 force, double term) {
      at.push_back(place), b.push_back(nb), a.push_back(na), f.push_back(force), old.push_back(term);
    }
  } owned;
};

}  // namespace cdem
