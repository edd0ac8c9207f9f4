// The two explosive models (SPEC 2 and 3), loading the rock each step after the block and
// spring forces.
//
// Bar model (SPEC 2, eq. 8-16): each deck is a bar from its initiation end, cut into segments
// no longer than the smallest element it crosses; each segment is bound to every elastic block
// its line passes through (clipping against the element's faces with a small tolerance, so a
// bar running along a face or an edge binds the elements on both sides). Per step:
//   theta_e = mean (J - 1) of the bound blocks, V = V0 (1 + theta_e)            (eq. 9)
//   P = Landau/JWL(V / V0)                                                      (eq. 10, 11)
//   t_1 = t_D0 + d_j / D, xi = clamp((t - t_1) D / h, 0, 1), P_r = xi P          (eq. 12, 13)
//   per bound block: P_bar = mean P_r of its segments, sigma_b = -P_bar (r0 / L_c)^a (eq. 14, 15)
//   nodal force F^N = -sigma_b sum over the faces k at N of n^k dS^k / (nodes of face k) (eq. 16)
// The factor (r0 / L_c)^a is capped at 1: an element smaller than the charge radius sees the
// full bar pressure, never more.
//
// Solid model (SPEC 3): explosive blocks (a region whose material names an explosive) inside
// a hole with model = "solid". Each gets P = lambda EOS(V / V0) with its current volume V and a
// programmed burn: ignition at t_D0 + |centroid - initiation point| / D, lambda rising from 0 to
// 1 over L_c / D. Pressure only (no shear stiffness); joined to the rock by unbreakable
// interfaces (mesh/topology.cpp). A block whose volume ratio falls below min_volume_ratio (or
// inverts) is reported once and stops carrying pressure.
#pragma once
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "cdem/explosive/eos.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/explosive/holes.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/applied_loads.hpp"

namespace cdem {

struct BarCharges {
  struct Bar {
    std::string hole;
    int deck = 0;
    std::int32_t eos = 0;        // index into eos
    double r0 = 0, D = 0, t0 = 0, length = 0, h = 0, attenuation = 1.25;
    bool cavity = true;          // the charge's share of a bound element is not rock (see below)
    bool lc_element_size = false;  // attenuation with L_c = element size (SPEC literal)
    Vec3 start, dir;             // initiation point and unit direction along the bar
    std::int32_t seg_begin = 0, seg_end = 0;
    GasModel gas = GasModel::Cracks;  // (its gas body is gas.bodies[bar index])
  };
  std::vector<Bar> bars;
  GasField gas;                                         // the decks' gas bodies (gas.hpp)
  std::vector<Eos> eos;
  // segments
  std::vector<std::int32_t> seg_bar;
  std::vector<double> seg_t_ign, seg_v0;   // ignition time (s), V0 = pi r0^2 h (3D) or 2 r0 h (2D)
  std::vector<std::int32_t> seg_elem_offset, seg_elem;  // CSR: segment -> bound blocks
  std::vector<double> seg_p, seg_v, seg_xi;             // state: P (Pa), V / V0, xi
  // loaded elements
  std::vector<std::int32_t> elem_block;
  std::vector<double> elem_atten;                       // min(1, (r0 / L_c)^a)
  std::vector<double> elem_phi;    // charge volume in the element / element volume (may be > 1)
  std::vector<std::uint8_t> elem_cavity;  // 1: hollowed by make_charge_cavities
  std::vector<std::int32_t> elem_seg_offset, elem_seg;  // CSR: element -> segments
  std::vector<double> elem_sigma;                       // applied pressure (Pa)
  // per loaded element, the charge volume each bar puts in it (CSR): elem_bar_offset,
  // elem_bar (bar index), elem_bar_vch (m^3)
  std::vector<std::int32_t> elem_bar_offset, elem_bar;
  std::vector<double> elem_bar_vch;
  double t_last = -1;                                   // time of the last bar_loads call

  bool empty() const { return bars.empty(); }
  std::size_t n_segments() const { return seg_bar.size(); }
};

// Builds the bars of every hole with model = "bar". Throws InputError naming the hole and deck
// when a bar leaves the mesh or crosses a void.
BarCharges build_bar_charges(const Model& m, const ChargeSpec& c);

// The charge occupies the fraction phi = min(1, elem_phi) of each bound element: that part of
// the element is explosive (a fluid whose pressure is the EOS), not rock (docs/theory.md,
// "Bar charges: the charge's share of the element"). For the bars with cavity = true, each
// bound block gets its own copy of its material with the rock's Lame constants scaled by its
// rock fraction (lambda' = (1 - phi) lambda, G' = (1 - phi) G: a Voigt mixture with a
// stiffness-free charge) and the density mixed by volume ((1 - phi) rho_rock + phi rho_w);
// the nodal masses follow. Call before the Simulation is built (time step, masses). Returns
// the time-step bound of the bound blocks, with the products' tangent stiffness (attenuated)
// added to their P-wave modulus (s; infinity if there are none).
double make_charge_cavities(Model& m, BarCharges& bars);

// One line for logs and `cdemblast check`: bars, segments, loaded blocks, the range of their
// charge fractions and attenuation factors.
std::string describe_bar_binding(const BarCharges& bars);

// Loads the rock at time t (adds to m.f through `out`): bar_state, then bar_apply.
void bar_loads(Model& m, BarCharges& bars, AppliedLoads& out, double t);
// The bars' state at time t (segments, gas bodies, each bound block's pressure elem_sigma) from
// the bound blocks' volume ratios `vol_ratio` (per block of m). With `given` the gas's crack list
// is the one given (gas_state), and m's state is not read, only its topology and sizes.
void bar_state(const Model& m, BarCharges& bars, std::span<const double> vol_ratio, double t,
               const CrackInputs* given = nullptr);
// The loads of that state: the gas-filled cracks' faces, then each bound block inflated by its
// pressure (eq. 16), and its stress the total stress (through `out`).
void bar_apply(Model& m, BarCharges& bars, AppliedLoads& out);

struct SolidCharges {
  struct Charge {
    std::string hole;
    int deck = 0;
    std::int32_t eos = 0;
    double D = 0;
  };
  std::vector<Charge> charges;
  std::vector<Eos> eos;
  std::vector<std::int32_t> block, charge;  // per explosive block
  std::vector<double> t_ign, burn_time, p, lambda, v0, v;  // v0: initial volume, v: V / V0
  std::vector<std::uint8_t> dead;
  std::vector<std::uint8_t> died_now;  // per explosive block: collapsed at the last step (solid_state)
  GasField gas;              // the decks' gas bodies (hole gas = cavity or cracks; gas.hpp)
  double t_last = -1;        // time of the last solid_loads call
  double min_volume_ratio = 0.05;
  std::int64_t dead_count = 0;
  double dt_limit = 0;  // min altitude / D over explosive blocks (s)

  bool empty() const { return block.empty(); }
};

// Binds every explosive block to the solid-model deck that contains it. Throws InputError for
// an explosive block outside every solid-model deck, or a solid-model hole with no blocks.
SolidCharges build_solid_charges(const Model& m, const ChargeSpec& c);

// Loads the rock from the explosive blocks at time t: each block's volume ratio into s.v,
// solid_gas_inputs, the gas (update_gas), solid_state, then per explosive block in order its
// volume ratio, a collapse's let_go_of_block, its stress and its inflation (inflate_block).
// A distributed run's part does the same from the volume ratios its owners formed
// (solver/halo_charges.hpp).
void solid_loads(Model& m, SolidCharges& s, AppliedLoads& out, double t);
// The gas bodies' burnt volume and cavity from the explosive blocks' volume ratios s.v at time t.
void solid_gas_inputs(SolidCharges& s, double t);
// After the gas state at time t: per explosive block its collapse (s.dead, s.died_now, the gas it
// takes with it; reported once), burnt fraction and pressure s.p. Reads s.v; of m only its
// element tags (the report).
void solid_state(const Model& m, SolidCharges& s, double t);
// A collapsed explosive block lets go of its neighbours: its points released (their stored
// energy booked as dissipated), tied mode its clusters split.
void let_go_of_block(Model& m, std::int32_t b);
// A block's signed volume (area in 2D) now over its initial one: <= 0 once it has inverted.
double current_volume_ratio(const Model& m, std::size_t b);
// A solid charge's explosive blocks are its products, a gas glued to the hole's wall by
// unbreakable interfaces: they take no part in general contact (Model::no_contact), from the
// start. (Their nodes were contact candidates once: the node at an open collar, driven out at
// km/s, and later the collapsed blocks' free nodes, made contact rebuild the pairs at nearly
// every step of the 3D solid case; docs/multihole_3d.md.) Called by the run's set-up.
void products_leave_contact(Model& m, const SolidCharges& s);

// charges.csv: per deck and time, the mean applied pressure, the charge volume ratio, the
// burnt fraction.
std::string charge_csv_header();
void write_charge_rows(std::FILE* f, double t, const BarCharges& bars, const SolidCharges& solids);

// Adds to the nodes of block b the forces of a uniform pressure p (Pa) on all its faces, in
// the current geometry: F^N = p sum_k n^k dS^k / n_k (outward: inflates; net force zero).
void inflate_block(Model& m, std::int32_t b, double p, AppliedLoads& out);
// Those forces, per node of the block (returns its node count).
int inflation_forces(const Model& m, std::int32_t b, double p, Vec3 fn[4]);

}  // namespace cdem
