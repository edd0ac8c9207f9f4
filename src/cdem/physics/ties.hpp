// Tied interfaces (simulation.interfaces = "tied", docs/theory.md "Tied interfaces"): the
// topology of the vertex clusters and the stiffness of opened points.
//
// Per mesh vertex, a cluster is a set of its nodes connected through tied spring points (the
// points whose two nodes are split from that vertex). A cluster moves as one: the step sums
// its nodes' forces and masses in a fixed order, integrates one velocity and gives every node
// of the cluster that velocity (integrate_tied, integrate.hpp), so the nodes of a cluster stay
// bitwise coincident and the intact rock is the conforming finite-element continuum: no
// interface compliance, and the time step of the blocks alone. A point that breaks is untied:
// the cluster of its vertex is recomputed locally (split_vertex), and the point then acts as
// the spring point of SPEC 1.3 (springs.hpp), with the stiffness of opened points
// (set_opened_stiffness), which is chosen so that it does not set the time step.
//
// Storage is sized at set-up: clusters only split (a broken point never heals), so the cluster
// of every node is a run of its vertex's node list, and a split only reorders that list.
#pragma once
#include <cstdint>

#include "cdem/model/model.hpp"

namespace cdem {

// Turns tied mode on: every intact spring point is tied (pre-cracked, i.e. broken, points are
// not), builds the vertex -> node lists and the clusters, the list of active interfaces (those
// with an untied point: pre-cracked joints) and their normals from the current positions. The
// nodes of each cluster get the cluster's mass-weighted mean velocity (one motion per cluster;
// an initial velocity field that is continuous is unchanged) and their first node's position.
// Tied points keep F_n = F_s = 0 (no spring force). Allocates sp_g0 (the offset that carries a
// point's force at the moment it is untied, springs.hpp).
void build_ties(Model& m);

// Recomputes the clusters of mesh vertex v from its tied points (union of the nodes they join),
// reordering v's node list: clusters ordered by their smallest node, nodes ascending in each.
// No allocation (uses Model::vtx_scratch).
void split_vertex(Model& m, std::int32_t v);

// Unties spring point s (no change of its force or state), activates its interface and splits
// the cluster of its vertex.
void untie_point(Model& m, std::size_t s);

// untie_point in two parts, for untying many points in parallel (tie_failure): the first unties
// s and splits the cluster of its vertex, touching only that vertex's nodes and tied points and
// scratch slot `slot` (< kMaxUntieThreads): any threads may run it at once for points of
// different vertices, each vertex's points one after the other in any order (the clusters are
// the same). The second activates interface i and updates its check flag (serially).
inline constexpr int kMaxUntieThreads = 64;
void untie_at_vertex(Model& m, std::size_t s, int slot);
void after_untie(Model& m, std::int32_t i);

// Puts interface i on the active list (its untied points get spring updates; its blocks gather
// spring forces) and sets its normal from the current positions.
void activate_interface(Model& m, std::int32_t i);

// Puts the active list back in ascending interface order: the interfaces activated since the last
// call (appended in the order they failed, scattered over the model) sorted and merged into it.
// The kernels that walk the list (spring_forces, the gas in the cracks) then read the interfaces'
// arrays in ascending order instead of one cache line per interface. Allocates nothing (the
// scratch is reserved at set-up); linear in the list's length when something was activated,
// nothing otherwise. A list restored from a checkpoint (active_sorted 0) is sorted whole once.
void order_active_ifaces(Model& m);

// The stiffness of opened points. The blocks alone are stable up to dt_b = 2 / omega_max, with
// omega_max^2 the largest element eigenvalue of M^-1 K over the elastic blocks (stable_step_tied,
// time_step.hpp). Each node n gets a stiffness budget eta omega_max^2 m_n / 2 shared by the
// c_n spring points at it, and each interface takes the smallest share of its points' nodes:
//   k_n A_c = min over the nodes n of its points of eta omega_max^2 m_n / (2 c_n),
//   k_s A_c = k_n A_c G / E (the softer block's, as SPEC 1.3).
// Then for any cluster C (mass M_C, the sum of its nodes' masses) the opened springs add at most
// sum 2 k / M_C <= eta omega_max^2 to the Gershgorin bound of M^-1 K, and by Weyl's inequality
// the whole model is stable for dt <= 2 / (omega_max sqrt(1 + eta)) with every point opened: the
// time step never has to change when clusters split. Returns the ratio of the chosen k_n to the
// springs mode's E / h (the penetration under a normal stress sigma is sigma h / (ratio E)):
// its minimum and median over the interfaces.
// The number of clusters (one per run of the vertex node lists).
std::size_t count_clusters(const Model& m);

struct OpenedStiffness {
  double ratio_min = 0, ratio_median = 0;
};
// `counts`: per node its spring-point count, when it is not m's own (a part of a distributed
// model: the whole model's).
OpenedStiffness set_opened_stiffness(Model& m, double eta, double omega2_max,
                                     const std::vector<std::int32_t>* counts = nullptr);

}  // namespace cdem
