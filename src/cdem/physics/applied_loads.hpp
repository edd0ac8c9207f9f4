// The record of the extra loads of a step (the explosive models', through the step's load hooks),
// for their work (solver/simulation.hpp, the energy balance).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// Forces applied by extra loads during a step, kept so that their work can be integrated with
// the mid-step velocity: W += F(n) . (v(n-1/2) + v(n+1/2)) / 2 dt. Each load's power with
// v(n-1/2) is kept as the load is added (old_terms), with v(n+1/2) after the integration
// (now_terms); the step sums both exactly (Simulation::step_sums).
struct AppliedLoads {
  std::vector<std::int32_t> node;  // single loads: f on node
  std::vector<Vec3> force;
  std::vector<std::int32_t> pair_b, pair_a;  // pair loads: f on pair_b, -f on pair_a
  std::vector<Vec3> pair_force;
  std::vector<double> old_terms;  // f . v(n-1/2) of each load added this step
  void clear() {
    node.clear();
    force.clear();
    pair_b.clear();
    pair_a.clear();
    pair_force.clear();
    old_terms.clear();
    owned.clear();
  }
  // Adds f to node n of the model and records it.
  void add(Model& m, std::int32_t n, Vec3 f) {
    m.f[n] += f;
    node.push_back(n);
    force.push_back(f);
    old_terms.push_back(dot(f, m.v[n]));
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
  // Books the pair loads' power terms power[0, n) (with v(n-1/2)). The caller adds their forces
  // itself, each node's in record order (update_gas: per block, in parallel).
  void book_pair_power(std::size_t n, const double* power) { old_terms.insert(old_terms.end(), power, power + n); }
  // Each load's f . v with the model's velocities now (after the integration: v(n+1/2)), into
  // `terms` (single loads, then pair loads; grown once).
  void now_terms(const Model& m);
  std::vector<double> terms;

  // A part of a distributed run (the halo stage, solver/halo_charges.hpp) does not record its
  // loads above: it lists here the loads it owns, each one's nodes (a < 0: a single load on b),
  // its force and its power with v(n-1/2). Every load of the whole model is owned by one part,
  // and the step's sums run over the owned loads of every part.
  struct Owned {
    std::vector<std::int32_t> b, a;
    std::vector<Vec3> f;
    std::vector<double> old;
    void clear() { b.clear(), a.clear(), f.clear(), old.clear(); }
    void add(std::int32_t nb, std::int32_t na, Vec3 force, double term) {
      b.push_back(nb), a.push_back(na), f.push_back(force), old.push_back(term);
    }
  } owned;
};

}  // namespace cdem
