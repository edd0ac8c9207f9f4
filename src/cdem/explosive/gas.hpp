// The bar's detonation products as gas bodies (`[[hole]] gas = "cavity"` or `"cracks"`; SPEC 2
// literal is gas = "literal"; docs/theory.md "Bar charges: the gas").
//
// Each deck is one gas body: its burnt mass m = rho_w sum_i xi_i V_i (V_i the charge volume a
// bound block i holds, xi_i its burnt fraction, eq. 12-13) fills one volume at one pressure
// (equalised along the deck):
//   V = sum_i xi_i [V_i + (J_i - 1) V0_i V_i / V_i,all]     the cavity: the charge plus the whole
//                                                          volume change of its bound blocks
//                                                          (the rock around is far stiffer than
//                                                          the gas: what the block gains in volume
//                                                          is the gas's), shared by the bars in
//                                                          the block by their charge volumes
//     + sum_cracks f_k A_k w_k                             the gas-filled cracks (model cracks)
//     + A_h x_p                                            the hole behind the moving plug
//   P = EOS(rho_w V / (m - m_vented))                      the isentrope (Landau or JWL) at the
//                                                          gas's specific volume
// Cracks (model cracks): an interface none of whose points is tied (intact) with a mean normal
// opening w_k > 0, next to a block the deck's gas has reached (its bound blocks to start with),
// fills at the speed of the choked flow c* = sqrt(gamma P / rho) (2 / (gamma + 1))^((gamma + 1)
// / (2 (gamma - 1))): its fill fraction f_k rises by c* dt / L_c per step; when full, the gas
// has reached the block beyond. A filled crack's faces are pushed apart by f_k P. Mass is
// conserved exactly: the gas has one density, rho = m / V, the crack mass is rho sum f A w.
// Venting, choked, at the rate C_d A_v rho c*: through the collar once the plug is out (or from
// ignition when the deck reaches the collar), A_v the hole's section, and through filled cracks
// that reach a block with a boundary face, A_v = w_k sqrt(A_k) (2D: w_k x 1 m).
// Plug: the collar stemming, mass rho_s A_h L_s, moves under P A_h against the wall shear
// tau_s (perimeter) (L_s - x) of its length still in the hole; out at x = L_s. Stemming between
// decks holds (not modelled).
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/explosive/eos.hpp"
#include "cdem/explosive/gas_model.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/applied_loads.hpp"

namespace cdem {

// One deck's products.
struct GasBody {
  // set-up
  GasModel model = GasModel::Cracks;
  std::int32_t eos = 0;        // index into the charge set's EOS table
  double rho_w = 0;            // explosive density (kg/m^3)
  double v0 = 0;               // charge volume (m^3; 2D per metre)
  double section = 0;          // hole cross-section (m^2; 2D m per metre)
  double plug_length = 0, plug_mass = 0, plug_shear = 0;  // collar stemming plug (m, kg, Pa)
  bool collar_open = false;    // an unstemmed collar that vents (a small charge in its top block)
  double vent_cd = 1.0;
  // state
  double burnt = 0;            // burnt mass (kg)
  double vented = 0;           // mass vented so far (kg), including the products of a solid
                               // charge's collapsed blocks, which leave with them
  double v_cavity = 0;         // volume of the burnt charge's cavity (m^3)
  double v_cracks = 0;         // volume of the gas-filled cracks (m^3)
  double m_cracks = 0;         // gas mass in them (kg)
  double pressure = 0;         // Pa
  double work = 0;             // int p dV of the gas (J)
  double v_prev = 0;           // last volume (m^3), for the work
  double plug_x = 0, plug_v = 0;  // plug displacement (m) and speed (m/s)
  bool plug_out = false;
  double vent_area = 0;        // this step's open vent area (m^2)
  double v_plug = 0;           // volume behind the moving plug, section x plug_x (m^3)
  double volume() const { return v_cavity + v_cracks + v_plug; }
  double gas_mass() const { return burnt - vented; }
};

// The gas bodies of one charge set (the bars, or the solid charges) and the gas in cracks.
struct GasField {
  std::vector<GasBody> bodies;
  // filled by the charge model each step, per body: burnt charge volume (m^3) and its cavity (m^3)
  std::vector<double> burnt_volume, cavity;
  // per interface the crack's fill fraction and the body whose gas it holds (-1 none); per block
  // the body whose gas reached it (-1 none), whether it has a boundary face; output: the crack
  // faces' gas pressure (Pa)
  std::vector<float> iface_fill, iface_gas_p;
  std::vector<std::int32_t> iface_body, block_body;
  std::vector<std::uint8_t> block_exterior;
  std::vector<double> scratch;
  // this step, per interface of the crack list (update_gas): open (every point untied / broken)
  // and its mean aperture (m); computed in parallel before the serial passes that use them
  std::vector<std::uint8_t> list_open;
  std::vector<double> list_aperture;  // (then, in the face-load pass, each one's gas pressure)
  std::vector<double> front_speed;    // this step, per body: the crack front's speed (m/s)
  // this step, per interface of the list, from the parallel part of the crack pass: what the
  // serial part does with it (bits), its body, its fill x area and its vent width (update_gas)
  std::vector<std::uint8_t> list_state;
  std::vector<std::int32_t> list_body;
  std::vector<double> list_fill_area, list_vent;
  // this step, the crack-face loads: per thread the first load of its range of the list
  // (prefix count of the threads' loads), per load its power term f . (v_b - v_a), filled in
  // parallel before the loads are applied (each node's in record order) and their power terms
  // summed in order
  std::vector<std::int64_t> thread_loads;
  std::vector<double> load_power;
  // per interface, this step: the index of its first crack-face load among them, -1 for none
  // (an interface off the list has none: in the tied mode the list only grows)
  std::vector<std::int32_t> iface_load;
  // a step with a given crack list (gas_state): set; the blocks the pass reached, and the first
  // interface whose front ran past what the list's rule covers (-1 none; CrackInputs)
  bool given_list = false;
  std::vector<std::int32_t> reached_now;
  std::int32_t chain_overflow = -1;
  bool any() const {
    for (const auto& b : bodies)
      if (b.model != GasModel::Literal) return true;
    return false;
  }
};

// Sizes the per-interface and per-block arrays of `g` for model m (bodies already added). A block is exterior (its gas vents) when it has a
// boundary face outside the face sets in `closed_sets`: the faces under a fixed, roller,
// non-reflecting or velocity condition are rock or a wall beyond the model, not a free surface.
void init_gas_field(const Model& m, GasField& g, const std::vector<std::string>& closed_sets);

// Seeds body k's gas in block b and, when `wall` is set, in b's face neighbours (the cavity's
// wall when the charge fills b).
void seed_gas(const Model& m, GasField& g, std::int32_t b, std::int32_t k, bool wall);

// The choked mass flux per unit vent area (kg/(m^2 s)) of gas at pressure p and density rho with
// isentropic exponent gamma.
double choked_mass_flux(double p, double rho, double gamma);

// The isentropic exponent of the products at relative volume v (Landau: gamma1 or gamma2 by
// stage; JWL: 1 + omega).
double products_gamma(const Eos& eos, double v);

// One step of the plug of a deck: gas pressure p, hole section a (m^2), perimeter c (m); advances
// x, v over dt and returns true once it is out (x >= length).
bool advance_plug(double& x, double& v, double p, double a, double c, double length, double mass,
                  double shear, double dt);

// One step of every body whose model is cavity or cracks, from the burnt volume and cavity the
// charge model has put in g.burnt_volume and g.cavity: mass, volume, pressure, venting, plug, the
// gas-filled cracks and their loads (added through `out`). dt: the time since the last call.
// It is gas_state, then gas_face_loads.
void update_gas(Model& m, GasField& g, const std::vector<Eos>& eos, AppliedLoads& out, double dt);

// An interface of the crack list is open when none of its points is tied (tied mode) or intact
// (springs mode); its aperture is its points' mean normal opening (m).
inline bool crack_open(const Model& m, std::size_t i) {
  const int np = m.springs_per_iface;
  for (int q = 0; q < np; ++q) {
    const auto s = i * np + q;
    if (m.tied ? m.sp_tied[s] != 0 : m.sp_state[s] == kIntact) return false;
  }
  return true;
}
inline double crack_aperture(const Model& m, std::size_t i) {
  const int np = m.springs_per_iface;
  double w = 0;
  const Vec3 n = m.iface_normal[i];
  for (int q = 0; q < np; ++q) w += dot(m.x[m.sp_b[i * np + q]] - m.x[m.sp_a[i * np + q]], n);
  return w / np;
}

// The crack list of a step given from outside (a distributed run's halo stage, where no rank holds
// every interface's state): its interfaces in ascending order, each with its open flag and
// aperture as its owner formed them. It need not hold the whole list, only every interface the
// pass would act on: every open one with a gas body, and every open one with a positive aperture
// that could take a body in the pass. A crack takes its body from a block the gas has reached;
// a block is reached in a pass when it has a body, or when a crack next to it with a body fills,
// or (rarely: a crack that fills in the step its gas reached it) when a crack without a body
// next to it fills from a block that has a body. So the rule is: an open crack with a body, or
// with a positive aperture and a block that has a body, or that is next to a crack with a body,
// or next to a block with one (gas_candidate). A front that goes further in one pass (a crack
// filling in the step its gas reached it, from a block reached in that pass) is reported in
// GasField::chain_overflow.
struct CrackInputs {
  std::vector<std::int32_t> iface;
  std::vector<std::uint8_t> open;
  std::vector<double> aperture;
};
// The rule above, for interface i of a model whose gas state `g` is (whole-model indices).
bool gas_candidate(const Model& m, const GasField& g, std::size_t i, bool open, double aperture);

// The state half of update_gas (the bodies, the crack fronts; no loads). With `given`, the crack
// list is the one given, and m's state (positions, ties) is not read: only its topology and sizes.
void gas_state(const Model& m, GasField& g, const std::vector<Eos>& eos, double dt,
               const CrackInputs* given = nullptr);
// The loads half: the filled cracks' faces pushed apart by f P (through `out`), over the list
// that gas_state used (not a given one).
void gas_face_loads(Model& m, GasField& g, AppliedLoads& out);

}  // namespace cdem
