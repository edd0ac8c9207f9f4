#include "cdem/explosive/charges.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cdem/core/error.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/springs.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/physics/ties.hpp"

namespace cdem {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Interval {
  double s0, s1;
  std::int32_t block;
};

// Clips the segment p + s d, s in [0, 1], against block b (reference configuration). Faces are
// widened by tol (m) so that a bar along a face or edge is inside both neighbours.
bool clip(const Model& m, std::int32_t b, Vec3 p, Vec3 d, double tol, double& s0, double& s1) {
  const auto n0 = m.block_first_node[b];
  const ElemType t = m.block_type[b];
  const LocalFaces lf = local_faces(t);
  s0 = 0.0;
  s1 = 1.0;
  for (int k = 0; k < lf.count; ++k) {
    Vec3 q[3];
    for (int i = 0; i < lf.nodes_per_face; ++i) q[i] = m.X(n0 + lf.f[k][i]);
    const Vec3 n = normalized(face_area_vector(std::span<const Vec3>(q, lf.nodes_per_face), lf.nodes_per_face));
    // inside: (p + s d - q0) . n <= tol
    const double a = dot(p - q[0], n) - tol, bd = dot(d, n);
    if (std::abs(bd) < 1e-300) {
      if (a > 0) return false;
      continue;
    }
    const double s = -a / bd;
    if (bd > 0)
      s1 = std::min(s1, s);
    else
      s0 = std::max(s0, s);
    if (s0 > s1) return false;
  }
  return s1 > s0;
}

void block_bbox(const Model& m, std::int32_t b, Vec3& lo, Vec3& hi) {
  lo = hi = m.X(m.block_first_node[b]);
  for (auto n = m.block_first_node[b] + 1; n < m.block_first_node[b + 1]; ++n)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], m.X(n)[k]);
      hi[k] = std::max(hi[k], m.X(n)[k]);
    }
}

std::int32_t eos_index(std::vector<Eos>& table, std::vector<std::string>& names,
                       const ChargeSpec& c, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<std::int32_t>(i);
  names.push_back(name);
  table.push_back(c.explosive(name)->eos);
  return static_cast<std::int32_t>(table.size() - 1);
}

}  // namespace

int inflation_forces(const Model& m, std::int32_t b, double p, Vec3 fn[4]) {
  const auto n0 = m.block_first_node[b];
  const LocalFaces lf = local_faces(m.block_type[b]);
  for (int i = 0; i < 4; ++i) fn[i] = Vec3{};
  for (int k = 0; k < lf.count; ++k) {
    Vec3 q[3];
    for (int i = 0; i < lf.nodes_per_face; ++i) q[i] = m.x[n0 + lf.f[k][i]];
    const Vec3 a = face_area_vector(std::span<const Vec3>(q, lf.nodes_per_face), lf.nodes_per_face);
    const Vec3 share = (p / lf.nodes_per_face) * a;
    for (int i = 0; i < lf.nodes_per_face; ++i) fn[lf.f[k][i]] += share;
  }
  return nodes_of(m.block_type[b]);
}

void inflate_block(Model& m, std::int32_t b, double p, AppliedLoads& out) {
  Vec3 fn[4];
  const int nn = inflation_forces(m, b, p, fn);
  const auto n0 = m.block_first_node[b];
  for (int i = 0; i < nn; ++i) out.add(m, n0 + i, fn[i]);
}

namespace {
// The top deck's gas body: the collar plug is the stemming above that deck (its length, mass
// and wall shear strength).
void set_collar_plug(GasBody& gb, const HoleDef& h, double section) {
  const Vec3 up = normalized(h.collar - h.end);
  const double top = dot(h.decks.back().top - h.end, up);
  double len = 0;
  for (const auto& st : h.stemming)
    if (st.first >= top - 1e-9) len += st.second - st.first;
  gb.plug_length = len;
  gb.plug_mass = h.stemming_density * section * len;
  gb.plug_shear = h.stemming_shear_strength;
}

}  // namespace

BarCharges build_bar_charges(const Model& m, const ChargeSpec& c) {
  BarCharges bc;
  std::vector<std::string> eos_names;
  std::vector<std::vector<std::int32_t>> elem_segs;  // by block, filled sparsely
  std::vector<std::int32_t> elem_slot(m.n_blocks(), -1);
  std::vector<double> vch(m.n_blocks(), 0.0);  // charge volume held by each block (m^3)
  std::vector<std::vector<std::pair<std::int32_t, double>>> bar_share(m.n_blocks());  // (bar, m^3)
  std::vector<Vec3> lo(m.n_blocks()), hi(m.n_blocks());
  for (std::size_t b = 0; b < m.n_blocks(); ++b) block_bbox(m, static_cast<std::int32_t>(b), lo[b], hi[b]);

  for (const auto& hole : c.holes) {
    if (hole.model != ChargeModel::Bar) continue;
    for (std::size_t di = 0; di < hole.decks.size(); ++di) {
      const Deck& deck = hole.decks[di];
      const std::string where = fmt::format("{}: hole '{}', deck {} ({} m of '{}')", c.path,
                                            hole.name, di + 1, deck.length, deck.explosive);
      BarCharges::Bar bar;
      bar.hole = hole.name;
      bar.deck = static_cast<int>(di);
      bar.eos = eos_index(bc.eos, eos_names, c, deck.explosive);
      bar.r0 = 0.5 * hole.diameter;
      bar.D = detonation_velocity(bc.eos[bar.eos]);
      bar.t0 = deck.delay;
      bar.length = deck.length;
      bar.attenuation = hole.attenuation_exponent;
      bar.cavity = hole.cavity;
      bar.lc_element_size = hole.lc_element_size;
      bar.start = deck.initiation();
      const Vec3 other = deck.initiate_top ? deck.bottom : deck.top;
      bar.dir = normalized(other - bar.start);
      const Vec3 d = other - bar.start;
      // ---- the blocks the bar's line passes through ----
      Vec3 blo = bar.start, bhi = bar.start;
      for (int k = 0; k < 3; ++k) {
        blo[k] = std::min(blo[k], other[k]);
        bhi[k] = std::max(bhi[k], other[k]);
      }
      std::vector<Interval> iv, cover;  // bound blocks; every block the bar touches (coverage)
      for (std::size_t b = 0; b < m.n_blocks(); ++b) {
        const double tol = 1e-6 * m.block_size[b];
        bool overlap = true;
        for (int k = 0; k < 3 && overlap; ++k)
          overlap = lo[b][k] - tol <= bhi[k] && blo[k] <= hi[b][k] + tol;
        if (!overlap) continue;
        double s0, s1;
        const auto bi = static_cast<std::int32_t>(b);
        // Keep a block only when the bar runs inside it over a real length (1e-4 L_c), so a
        // block that touches the bar at a corner or at the bar's end point is not bound, while
        // a bar along a face or edge (widened by tol) binds the blocks on both sides.
        if (!clip(m, bi, bar.start, d, tol, s0, s1)) continue;
        cover.push_back({s0, s1, bi});
        if ((s1 - s0) * bar.length > 1e-4 * m.block_size[b]) {
          if (!m.block_materials[m.block_material[b]].explosive.empty())
            throw InputError(fmt::format("{}: the bar runs through explosive blocks (region '{}'); "
                                         "a bar charge needs rock around it: give the region a rock "
                                         "material or set the hole's model = \"solid\"",
                                         where, m.region_names[m.block_region[b]]));
          iv.push_back({s0, s1, bi});
        }
      }
      // ---- coverage: the bar must lie inside the mesh over its whole length (checked with every
      // block it touches, so passing a vertex closely is not mistaken for a void) ----
      std::sort(cover.begin(), cover.end(), [](const Interval& a, const Interval& b) { return a.s0 < b.s0; });
      double reach = 0.0;
      const double gap_tol = 1e-6;
      for (const auto& x : cover) {
        if (x.s0 > reach + gap_tol) break;
        reach = std::max(reach, x.s1);
      }
      if (iv.empty() || reach < 1.0 - gap_tol) {
        const Vec3 p = bar.start + (reach * bar.length) * bar.dir;
        throw InputError(fmt::format("{}: the bar leaves the mesh or crosses a void {:.4g} m from "
                                     "its initiation point, at ({:.4g}, {:.4g}, {:.4g}); a bar "
                                     "must lie inside rock elements over its whole length",
                                     where, reach * bar.length, p.x, p.y, p.z));
      }
      // ---- the charge volume each bound block holds: the blocks bound over a stretch of the
      // bar host the charge of that stretch together, each in proportion to the volume it
      // brings to the stretch (its volume x the stretch's share of its bound length). So every
      // block bound over a stretch has the same charge fraction phi = charge volume / host
      // volume: 1 when the bound blocks exactly fill the hole, < 1 when they are larger ----
      const double section = m.dim == 3 ? kPi * bar.r0 * bar.r0 : 2.0 * bar.r0;
      {
        std::vector<double> cuts;
        for (const auto& x : iv) {
          cuts.push_back(std::clamp(x.s0, 0.0, 1.0));
          cuts.push_back(std::clamp(x.s1, 0.0, 1.0));
        }
        std::sort(cuts.begin(), cuts.end());
        for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
          const double u0 = cuts[k], u1 = cuts[k + 1];
          if (!(u1 > u0)) continue;
          const double mid = 0.5 * (u0 + u1);
          double host = 0;
          for (const auto& x : iv)
            if (x.s0 <= mid && mid <= x.s1) host += m.block_volume0[x.block] * (u1 - u0) / (x.s1 - x.s0);
          if (!(host > 0)) continue;
          const double phi = section * (u1 - u0) * bar.length / host;
          for (const auto& x : iv)
            if (x.s0 <= mid && mid <= x.s1) {
              const double share = phi * m.block_volume0[x.block] * (u1 - u0) / (x.s1 - x.s0);
              vch[x.block] += share;
              auto& lst = bar_share[x.block];
              const auto kbar = static_cast<std::int32_t>(bc.bars.size());
              if (lst.empty() || lst.back().first != kbar) lst.push_back({kbar, 0.0});
              lst.back().second += share;
            }
        }
      }
      // A bar loads only the blocks on its line: when they are much smaller than the charge
      // (a mesh finer than the hole), part of the hole wall is not loaded.
      {
        double host = 0;
        for (const auto& x : iv) host += m.block_volume0[x.block];
        const double charge = section * bar.length;
        if (charge > 1.5 * host)
          spdlog::warn("{}: the {} blocks the bar runs through have {:.3g} m3{} in all against "
                       "the charge's {:.3g} m3: they are smaller than the hole, and the bar loads "
                       "only them, not the hole's wall (the bar model is meant for elements at "
                       "least as large as the hole: coarsen the mesh at the hole, or use the "
                       "solid model)",
                       where, iv.size(), host, m.dim == 2 ? " (per metre)" : "", charge);
      }
      // ---- segmentation: no longer than the smallest crossed element ----
      double hmin = std::numeric_limits<double>::infinity();
      for (const auto& x : iv) hmin = std::min(hmin, m.block_size[x.block]);
      const int nseg = std::max(1, static_cast<int>(std::ceil(bar.length / hmin - 1e-9)));
      bar.h = bar.length / nseg;
      bar.seg_begin = static_cast<std::int32_t>(bc.seg_bar.size());
      if (bc.seg_elem_offset.empty()) bc.seg_elem_offset.push_back(0);
      for (int j = 0; j < nseg; ++j) {
        const double a0 = static_cast<double>(j) / nseg, a1 = static_cast<double>(j + 1) / nseg;
        const auto sj = static_cast<std::int32_t>(bc.seg_bar.size());
        bc.seg_bar.push_back(static_cast<std::int32_t>(bc.bars.size()));
        const double dj = (j + 0.5) * bar.h;  // distance of the centre from the initiation point
        bc.seg_t_ign.push_back(bar.t0 + dj / bar.D);
        bc.seg_v0.push_back(section * bar.h);  // eq. 8 (plane strain: 2 r0 h per metre)
        for (const auto& x : iv) {
          const double ov = std::min(a1, x.s1) - std::max(a0, x.s0);
          if (ov * bar.length <= 1e-4 * m.block_size[x.block]) continue;
          bc.seg_elem.push_back(x.block);
          if (elem_slot[x.block] < 0) {
            elem_slot[x.block] = static_cast<std::int32_t>(bc.elem_block.size());
            bc.elem_block.push_back(x.block);
            bc.elem_atten.push_back(0.0);  // set below, once every bar's share is known
            elem_segs.emplace_back();
          }
          elem_segs[elem_slot[x.block]].push_back(sj);
        }
        bc.seg_elem_offset.push_back(static_cast<std::int32_t>(bc.seg_elem.size()));
      }
      bar.seg_end = static_cast<std::int32_t>(bc.seg_bar.size());
      // the deck's gas body (gas.hpp)
      bar.gas = hole.gas;
      {
        GasBody gb;
        gb.model = hole.gas;
        gb.eos = bar.eos;
        gb.rho_w = explosive_density(bc.eos[bar.eos]);
        gb.v0 = section * bar.length;
        gb.section = section;
        gb.vent_cd = hole.vent_coefficient;
        if (di + 1 == hole.decks.size()) {
          set_collar_plug(gb, hole, section);
          gb.collar_open = gb.plug_length <= 1e-9 * hole.length();
        }
        bc.gas.bodies.push_back(gb);
      }
      bc.bars.push_back(bar);
    }
  }
  // ---- attenuation (eq. 15) with L_c the element's equivalent radius about the bar: the radius
  // of the cylinder (3D) or the half-width of the strip (plane strain) that has the element's
  // volume and holds the element's share of the charge over the same length. Then
  // (r0 / L_c)^2 = phi in 3D and r0 / L_c = phi in 2D, phi = charge volume / element volume:
  // a charge that fills its element is not attenuated; one much smaller than its element is.
  // (A size taken as the element's edge length would compare a radius with a diameter and
  // attenuate even a charge that exactly fills its element.) ----
  bc.elem_phi.resize(bc.elem_block.size());
  bc.elem_cavity.assign(bc.elem_block.size(), 0);
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const auto b = bc.elem_block[i];
    const double phi = vch[b] / m.block_volume0[b];
    bc.elem_phi[i] = phi;
    const double r_over_lc = m.dim == 3 ? std::sqrt(phi) : phi;
    const auto& bar = bc.bars[bc.seg_bar[elem_segs[i].front()]];
    for (auto sj : elem_segs[i]) {
      const auto& other = bc.bars[bc.seg_bar[sj]];
      if (other.attenuation != bar.attenuation || other.lc_element_size != bar.lc_element_size)
        throw InputError(fmt::format("{}: block {} (element {}) holds the charges of holes '{}' and "
                                     "'{}' with different attenuation settings (exponents {} and {}, "
                                     "or attenuation_length); give them the same",
                                     c.path, b, m.block_elem_tag[b], bar.hole, other.hole,
                                     bar.attenuation, other.attenuation));
    }
    const double rl = bar.lc_element_size ? bar.r0 / m.block_size[b] : r_over_lc;
    bc.elem_atten[i] = std::min(1.0, std::pow(rl, bar.attenuation));
  }
  bc.elem_seg_offset.assign(1, 0);
  for (const auto& v : elem_segs) {
    bc.elem_seg.insert(bc.elem_seg.end(), v.begin(), v.end());
    bc.elem_seg_offset.push_back(static_cast<std::int32_t>(bc.elem_seg.size()));
  }
  bc.elem_bar_offset.assign(1, 0);
  for (const auto b : bc.elem_block) {
    for (const auto& [k, v] : bar_share[b]) {
      bc.elem_bar.push_back(k);
      bc.elem_bar_vch.push_back(v);
    }
    bc.elem_bar_offset.push_back(static_cast<std::int32_t>(bc.elem_bar.size()));
  }
  init_gas_field(m, bc.gas, c.closed_face_sets);
  // The gas starts in the blocks that hold the charge; where the charge fills its blocks (phi >=
  // 0.5: charge blocks, glued to their neighbours) the cavity's wall is the neighbours' faces.
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i)
    for (auto e = bc.elem_bar_offset[i]; e < bc.elem_bar_offset[i + 1]; ++e)
      seed_gas(m, bc.gas, bc.elem_block[i], bc.elem_bar[e], bc.elem_phi[i] >= 0.5);
  // An unstemmed collar vents only where the charge is a small part of its top block: where it
  // fills its blocks (phi >= 0.5) the top block's own stretching past the collar is the products'
  // escape, as for a solid charge's explosive blocks.
  for (std::size_t k = 0; k < bc.bars.size(); ++k) {
    GasBody& gb = bc.gas.bodies[k];
    if (!gb.collar_open) continue;
    const auto& bar = bc.bars[k];
    const Vec3 top = bar.start + bar.length * bar.dir;
    double best = std::numeric_limits<double>::infinity(), phi = 0;
    for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
      const auto b = bc.elem_block[i];
      Vec3 cen{};
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) cen += m.X(n);
      cen = cen / (m.block_first_node[b + 1] - m.block_first_node[b]);
      const double d = norm(cen - top);
      if (d < best) best = d, phi = bc.elem_phi[i];
    }
    if (phi >= 0.5) gb.collar_open = false;
  }
  bc.seg_p.assign(bc.seg_bar.size(), 0.0);
  bc.seg_v.assign(bc.seg_bar.size(), 1.0);
  bc.seg_xi.assign(bc.seg_bar.size(), 0.0);
  bc.elem_sigma.assign(bc.elem_block.size(), 0.0);
  return bc;
}

std::string describe_bar_binding(const BarCharges& bc) {
  double phi_lo = std::numeric_limits<double>::infinity(), phi_hi = 0;
  double att_lo = std::numeric_limits<double>::infinity(), att_hi = 0;
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    phi_lo = std::min(phi_lo, bc.elem_phi[i]);
    phi_hi = std::max(phi_hi, bc.elem_phi[i]);
    att_lo = std::min(att_lo, bc.elem_atten[i]);
    att_hi = std::max(att_hi, bc.elem_atten[i]);
  }
  return fmt::format("{} bars, {} segments, {} loaded blocks; charge volume / block volume "
                     "{:.3g} to {:.3g}, attenuation {:.3g} to {:.3g}",
                     bc.bars.size(), bc.n_segments(), bc.elem_block.size(), phi_lo, phi_hi, att_lo,
                     att_hi);
}

void bar_loads(Model& m, BarCharges& bc, AppliedLoads& out, double t) {
  bar_state(m, bc, m.vol_ratio, t);
  bar_apply(m, bc, out);
}

void bar_state(const Model& m, BarCharges& bc, std::span<const double> vol_ratio, double t,
               const CrackInputs* given) {
  const std::size_t ns = bc.n_segments();
  for (std::size_t j = 0; j < ns; ++j) {
    const auto& bar = bc.bars[bc.seg_bar[j]];
    const double xi = std::clamp((t - bc.seg_t_ign[j]) * bar.D / bar.h, 0.0, 1.0);  // eq. 12, 13
    bc.seg_xi[j] = xi;
    if (bar.gas != GasModel::Literal) continue;  // the deck's gas body (gas.hpp)
    double theta = 0;
    const auto e0 = bc.seg_elem_offset[j], e1 = bc.seg_elem_offset[j + 1];
    for (auto e = e0; e < e1; ++e) theta += vol_ratio[bc.seg_elem[e]] - 1.0;
    const double v = 1.0 + theta / (e1 - e0);                               // eq. 9
    bc.seg_v[j] = v;
    bc.seg_p[j] = xi > 0 ? xi * eos_pressure(bc.eos[bar.eos], v) : 0.0;     // eq. 10, 11
  }
  if (bc.gas.any()) {
    // Each deck's burnt charge and its cavity: the charge volume V_i a bound block holds plus
    // the block's whole volume change, shared by the bars in it by charge volume, times the
    // block's burnt fraction for the bar (the mean of its segments of the bar).
    std::fill(bc.gas.burnt_volume.begin(), bc.gas.burnt_volume.end(), 0.0);
    std::fill(bc.gas.cavity.begin(), bc.gas.cavity.end(), 0.0);
    for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
      const auto b = bc.elem_block[i];
      double all = 0;
      for (auto e = bc.elem_bar_offset[i]; e < bc.elem_bar_offset[i + 1]; ++e) all += bc.elem_bar_vch[e];
      if (!(all > 0)) continue;
      // (a collapsed or inverted block holds no gas: J taken as 0 at most)
      const double dv = (std::max(vol_ratio[b], 0.0) - 1.0) * m.block_volume0[b];
      for (auto e = bc.elem_bar_offset[i]; e < bc.elem_bar_offset[i + 1]; ++e) {
        const auto k = bc.elem_bar[e];
        if (bc.bars[k].gas == GasModel::Literal) continue;
        double xi = 0;
        int n = 0;
        for (auto q = bc.elem_seg_offset[i]; q < bc.elem_seg_offset[i + 1]; ++q)
          if (bc.seg_bar[bc.elem_seg[q]] == k) xi += bc.seg_xi[bc.elem_seg[q]], ++n;
        xi = n ? xi / n : 0.0;
        const double vch = bc.elem_bar_vch[e];
        bc.gas.burnt_volume[k] += xi * vch;
        bc.gas.cavity[k] += xi * (vch + dv * vch / all);
      }
    }
    gas_state(m, bc.gas, bc.eos, bc.t_last >= 0 ? t - bc.t_last : 0.0, given);
    for (std::size_t k = 0; k < bc.bars.size(); ++k) {
      const auto& bar = bc.bars[k];
      if (bar.gas == GasModel::Literal) continue;
      const GasBody& gb = bc.gas.bodies[k];
      for (auto j = bar.seg_begin; j < bar.seg_end; ++j) {
        bc.seg_p[j] = bc.seg_xi[j] > 0 ? bc.seg_xi[j] * gb.pressure : 0.0;  // eq. 13, deck P
        bc.seg_v[j] = gb.v0 > 0 ? gb.volume() / gb.v0 : 1.0;
      }
    }
  }
  bc.t_last = t;
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    double pbar = 0;
    const auto s0 = bc.elem_seg_offset[i], s1 = bc.elem_seg_offset[i + 1];
    for (auto s = s0; s < s1; ++s) pbar += bc.seg_p[bc.elem_seg[s]];
    pbar /= (s1 - s0);                                                      // eq. 14
    bc.elem_sigma[i] = pbar * bc.elem_atten[i];                             // eq. 15
  }
}

void bar_apply(Model& m, BarCharges& bc, AppliedLoads& out) {
  // the gas-filled cracks' faces first, then the bound blocks (each node's forces in that order)
  if (bc.gas.any()) gas_face_loads(m, bc.gas, out);
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    if (bc.elem_sigma[i] > 0) {
      const auto b = bc.elem_block[i];
      inflate_block(m, b, bc.elem_sigma[i], out);                           // eq. 16
      // The block's total stress: its rock skeleton's plus the products' pressure on its faces,
      // sigma - sigma_b I (as a solid charge's block reports -p I). The traction a tied face
      // transmits (tie_failure) and the outputs see it; the dynamics are the nodal forces above.
      for (int k = 0; k < 3; ++k) m.stress[b][k] -= bc.elem_sigma[i];
    }
  }
}

double make_charge_cavities(Model& m, BarCharges& bc) {
  double dt = std::numeric_limits<double>::infinity();
  std::vector<std::uint8_t> glue(m.n_blocks(), 0);  // blocks that count as charge (phi >= 0.5)
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const auto b = bc.elem_block[i];
    // The bars bound to this block: one explosive and one `cavity` setting per block (a block
    // shared by two bars takes the density and the stiffest products of the two).
    double rho_w = 0, keos = 0, wsum = 0;
    bool cavity = false, first = true;
    for (auto q = bc.elem_seg_offset[i]; q < bc.elem_seg_offset[i + 1]; ++q) {
      const auto& bar = bc.bars[bc.seg_bar[bc.elem_seg[q]]];
      if (!first && bar.cavity != cavity)
        throw InputError(fmt::format("hole '{}': block {} (element {}) holds the charges of holes "
                                     "with different 'cavity' settings; give them the same",
                                     bar.hole, b, m.block_elem_tag[b]));
      cavity = bar.cavity;
      first = false;
      const auto& eos = bc.eos[bar.eos];
      rho_w += explosive_density(eos);
      wsum += 1.0;
      // The products stiffen the block: K_eos = -dP/dv at v = 1 (tangent of the isentrope,
      // by a central difference).
      const double dv = 1e-4;
      keos = std::max(keos, (eos_pressure(eos, 1.0 - dv) - eos_pressure(eos, 1.0 + dv)) / (2.0 * dv));
    }
    rho_w /= wsum;
    const auto k = m.block_material[b];
    const double lam = m.mat_lambda[k], G = m.mat_shear[k];
    const double rho = m.block_materials[k].density;
    double lam_c = lam, G_c = G, rho_c = rho;
    if (cavity) {
      const double phi = std::min(1.0, bc.elem_phi[i]);
      lam_c = (1.0 - phi) * lam;
      G_c = (1.0 - phi) * G;
      rho_c = (1.0 - phi) * rho + phi * rho_w;
      BlockMaterial mat = m.block_materials[k];
      mat.name = fmt::format("{} + bar charge (phi {:.3g})", mat.name, phi);
      mat.density = rho_c;
      mat.youngs *= 1.0 - phi;  // nu kept: lambda and G scale alike, cp() and cs() agree
      mat.charge_fraction = phi;
      mat.products_mass = phi * rho_w / rho_c;
      mat.charge_block = bc.elem_phi[i] >= 0.5;
      if (mat.charge_block) glue[b] = 1;
      m.block_materials.push_back(mat);
      m.mat_lambda.push_back(lam_c);
      m.mat_shear.push_back(G_c);
      m.mat_beta.push_back(mat.stiffness_damping);
      m.block_material[b] = static_cast<std::int32_t>(m.block_materials.size() - 1);
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
        m.mass[n] *= rho_c / rho;
        m.inv_mass[n] = 1.0 / m.mass[n];
      }
      bc.elem_cavity[i] = 1;
    }
    // P-wave modulus of the block with the products' tangent stiffness, attenuated like the
    // pressure: lambda' + 2G' + att K_eos.
    const double c = std::sqrt((lam_c + 2.0 * G_c + bc.elem_atten[i] * keos) / rho_c);
    dt = std::min(dt, m.block_altitude0[b] / c);
  }
  // A block that is mostly charge (phi >= 0.5) is held together by the charge, not the rock:
  // like the solid model's explosive blocks (SPEC 3) it is joined to its neighbours by
  // unbreakable interfaces (the hole wall confines the products; without it a nearly
  // stiffness-free block whose interfaces break has free nodes that the pressure throws
  // apart). Blocks that are mostly rock keep the rock's interfaces and can crack.
  std::int32_t contact = -1;
  for (std::size_t f = 0; f < m.n_ifaces(); ++f) {
    if (!glue[m.iface_block_a[f]] && !glue[m.iface_block_b[f]]) continue;
    if (contact < 0) {
      InterfaceMaterial im;
      im.name = "charge_contact";
      im.law = InterfaceLaw::Elastic;
      m.iface_materials.push_back(im);
      m.spring_laws.push_back(make_spring_law(im));
      contact = static_cast<std::int32_t>(m.iface_materials.size() - 1);
    }
    m.iface_material[f] = contact;
    for (int q = 0; q < m.springs_per_iface; ++q)
      m.sp_state[f * m.springs_per_iface + q] = kIntact;  // (a pre-cracked joint is glued too)
  }
  return dt;
}

SolidCharges build_solid_charges(const Model& m, const ChargeSpec& c) {
  SolidCharges sc;
  std::vector<std::string> eos_names;
  struct DeckRef {
    const HoleDef* hole;
    std::size_t deck;
    std::int32_t charge;
  };
  std::vector<DeckRef> decks;
  for (const auto& h : c.holes) {
    if (h.model != ChargeModel::Solid) continue;
    for (std::size_t d = 0; d < h.decks.size(); ++d) {
      SolidCharges::Charge ch;
      ch.hole = h.name;
      ch.deck = static_cast<int>(d);
      ch.eos = eos_index(sc.eos, eos_names, c, h.decks[d].explosive);
      ch.D = detonation_velocity(sc.eos[ch.eos]);
      decks.push_back({&h, d, static_cast<std::int32_t>(sc.charges.size())});
      sc.charges.push_back(ch);
      // the deck's gas body (gas.hpp): its cavity is its explosive blocks' volume
      GasBody gb;
      gb.model = h.gas;
      gb.eos = ch.eos;
      gb.rho_w = explosive_density(sc.eos[ch.eos]);
      const double section = m.dim == 3 ? kPi * 0.25 * h.diameter * h.diameter : h.diameter;
      gb.section = section;
      gb.vent_cd = h.vent_coefficient;
      if (d + 1 == h.decks.size()) set_collar_plug(gb, h, section);
      sc.gas.bodies.push_back(gb);
    }
  }
  std::vector<int> used(sc.charges.size(), 0);
  sc.dt_limit = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    if (m.block_materials[m.block_material[b]].explosive.empty()) continue;
    Vec3 cen{};
    const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
    for (auto n = n0; n < n1; ++n) cen += m.X(n);
    cen = cen / (n1 - n0);
    // The deck whose axis segment is nearest, within its radius plus the block size.
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < decks.size(); ++k) {
      const Deck& d = decks[k].hole->decks[decks[k].deck];
      const Vec3 ax = d.top - d.bottom;
      const double s = std::clamp(dot(cen - d.bottom, ax) / dot(ax, ax), 0.0, 1.0);
      const double dist = norm(cen - (d.bottom + s * ax));
      if (dist <= 0.5 * decks[k].hole->diameter + 0.5 * m.block_size[b] && dist < best_d) {
        best_d = dist;
        best = static_cast<int>(k);
      }
    }
    if (best < 0)
      throw InputError(fmt::format("{}: explosive block (element {} of region '{}') at ({:.4g}, "
                                   "{:.4g}, {:.4g}) is not inside the charge of any hole with "
                                   "model = \"solid\"",
                                   c.path, m.block_elem_tag[b], m.region_names[m.block_region[b]],
                                   cen.x, cen.y, cen.z));
    const auto& ref = decks[best];
    const Deck& d = ref.hole->decks[ref.deck];
    const double D = sc.charges[ref.charge].D;
    sc.block.push_back(static_cast<std::int32_t>(b));
    sc.charge.push_back(ref.charge);
    sc.t_ign.push_back(d.delay + norm(cen - d.initiation()) / D);
    sc.burn_time.push_back(m.block_size[b] / D);
    sc.v0.push_back(m.block_volume0[b]);
    sc.dt_limit = std::min(sc.dt_limit, m.block_altitude0[b] / D);
    used[ref.charge] = 1;
  }
  for (std::size_t k = 0; k < sc.charges.size(); ++k)
    if (!used[k])
      throw InputError(fmt::format("{}: hole '{}' (model = \"solid\"), deck {}: no explosive blocks "
                                   "inside it; mesh the charge as a region whose material has "
                                   "'explosive' set",
                                   c.path, sc.charges[k].hole, sc.charges[k].deck + 1));
  init_gas_field(m, sc.gas, c.closed_face_sets);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    seed_gas(m, sc.gas, sc.block[i], sc.charge[i], true);
    sc.gas.bodies[sc.charge[i]].v0 += sc.v0[i];
  }
  sc.p.assign(sc.block.size(), 0.0);
  sc.lambda.assign(sc.block.size(), 0.0);
  sc.dead.assign(sc.block.size(), 0);
  sc.v.assign(sc.block.size(), 1.0);
  return sc;
}

// A block's signed volume (area in 2D) now over its initial one: <= 0 once it has inverted.
double current_volume_ratio(const Model& m, std::size_t b) {
  const auto n0 = m.block_first_node[b];
  const int nn = nodes_of(m.block_type[b]);
  Vec3 p[4];
  for (int k = 0; k < nn; ++k) p[k] = m.x[n0 + k];
  return signed_measure(m.block_type[b], std::span<const Vec3>(p, nn)) / m.block_volume0[b];
}

void products_leave_contact(Model& m, const SolidCharges& s) {
  if (s.block.empty()) return;
  if (m.no_contact.empty()) m.no_contact.assign(m.n_blocks(), 0);
  for (auto b : s.block) m.no_contact[b] = 1;
}

void solid_loads(Model& m, SolidCharges& sc, AppliedLoads& out, double t) {
  for (std::size_t i = 0; i < sc.block.size(); ++i) sc.v[i] = current_volume_ratio(m, sc.block[i]);
  solid_gas_inputs(sc, t);
  if (sc.gas.any()) update_gas(m, sc.gas, sc.eos, out, sc.t_last >= 0 ? t - sc.t_last : 0.0);
  solid_state(m, sc, t);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    const auto b = sc.block[i];
    m.vol_ratio[b] = sc.v[i];
    if (sc.died_now[i]) let_go_of_block(m, b);
    const double pr = sc.p[i];
    m.stress[b] = {-pr, -pr, -pr, 0, 0, 0};
    if (pr > 0) inflate_block(m, b, pr, out);
  }
}

void solid_gas_inputs(SolidCharges& sc, double t) {
  // Decks with a gas body (gas = cavity or cracks): one pressure per deck from the burnt
  // blocks' total volume (a collapsing block no longer gets the pressure of its own tiny volume).
  if (!sc.gas.any()) return;
  std::fill(sc.gas.burnt_volume.begin(), sc.gas.burnt_volume.end(), 0.0);
  std::fill(sc.gas.cavity.begin(), sc.gas.cavity.end(), 0.0);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    const double v = sc.v[i];
    const double lam = std::clamp((t - sc.t_ign[i]) / sc.burn_time[i], 0.0, 1.0);
    sc.gas.burnt_volume[sc.charge[i]] += lam * sc.v0[i];
    // a collapsed block has been let go with its products (booked as vented when it died)
    if (!sc.dead[i]) sc.gas.cavity[sc.charge[i]] += lam * std::max(v, 0.0) * sc.v0[i];
  }
}

void solid_state(const Model& m, SolidCharges& sc, double t) {
  sc.t_last = t;
  sc.died_now.assign(sc.block.size(), 0);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    const auto b = sc.block[i];
    const double v = sc.v[i];
    if (!sc.dead[i] && !(v > sc.min_volume_ratio)) {
      sc.dead[i] = 1;
      sc.died_now[i] = 1;
      ++sc.dead_count;
      {  // its share of the deck's gas leaves with it
        GasBody& gb = sc.gas.bodies[sc.charge[i]];
        const double lam0 = std::clamp((t - sc.t_ign[i]) / sc.burn_time[i], 0.0, 1.0);
        const double total = gb.v0 > 0 ? gb.gas_mass() * sc.v0[i] / gb.v0 : 0.0;
        if (gb.model != GasModel::Literal) gb.vented += std::min(total, lam0 * gb.rho_w * sc.v0[i]);
      }
      spdlog::warn("t = {:.6g} s: explosive block {} (element {}) collapsed (volume ratio {:.3g}); "
                   "it stops carrying pressure and is let go of its neighbours",
                   t, b, m.block_elem_tag[b], v);
    }
    const auto& ch = sc.charges[sc.charge[i]];
    const double lam = std::clamp((t - sc.t_ign[i]) / sc.burn_time[i], 0.0, 1.0);
    sc.lambda[i] = lam;
    const GasBody& gb = sc.gas.bodies[sc.charge[i]];
    const double p_products = gb.model == GasModel::Literal ? eos_pressure(sc.eos[ch.eos], v) : gb.pressure;
    sc.p[i] = (sc.dead[i] || lam <= 0) ? 0.0 : lam * p_products;
  }
}

void let_go_of_block(Model& m, std::int32_t b) {
  // Its unbreakable interfaces would otherwise keep pulling the rock blocks around it into
  // the collapse (SPEC 5.2 study: a tied rock block inverted next). Their stored energy is
  // booked as dissipated, so the energy balance stays closed.
  for_each_block_spring(m, b, [&m](std::size_t sp) {
    if (m.sp_state[sp] == kReleased) return;
    if (m.tied) untie_point(m, sp);  // tied mode: its clusters split (ties.hpp)
    m.sp_dissipated[sp] += 0.5 * m.sp_fn[sp] * m.sp_fn[sp] / m.sp_kn[sp] +
                           0.5 * dot(m.sp_fs[sp], m.sp_fs[sp]) / m.sp_ks[sp];
    m.sp_state[sp] = kReleased;
    ++m.released_points;
    m.sp_fn[sp] = 0;
    m.sp_fs[sp] = {};
  });
}

std::string charge_csv_header() {
  return "time,hole,deck,model,pressure,volume_ratio,burnt_fraction,gas_volume,gas_mass_charge,"
         "gas_mass_cracks,vented_mass,gas_work,plug_displacement\n";
}

void write_charge_rows(std::FILE* f, double t, const BarCharges& bc, const SolidCharges& sc) {
  for (const auto& bar : bc.bars) {
    double p = 0, v = 0, xi = 0;
    const int n = bar.seg_end - bar.seg_begin;
    for (auto j = bar.seg_begin; j < bar.seg_end; ++j) {
      p += bc.seg_p[j];
      v += bc.seg_v[j];
      xi += bc.seg_xi[j];
    }
    const std::size_t k = static_cast<std::size_t>(&bar - bc.bars.data());
    const GasBody& gs = bc.gas.bodies[k];
    if (bar.gas == GasModel::Literal) {
      std::fprintf(f, "%.9g,%s,%d,bar,%.9g,%.9g,%.9g,%.9g,%.9g,0,0,0,0\n", t, bar.hole.c_str(),
                   bar.deck + 1, p / n, v / n, xi / n, gs.v0 * v / n, gs.rho_w * gs.v0 * xi / n);
    } else {
      const double vol = gs.volume(), mgas = gs.gas_mass();
      std::fprintf(f, "%.9g,%s,%d,bar,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", t,
                   bar.hole.c_str(), bar.deck + 1, gs.pressure, gs.v0 > 0 ? vol / gs.v0 : 1.0,
                   xi / n, vol, mgas - gs.m_cracks, gs.m_cracks, gs.vented, gs.work, gs.plug_x);
    }
  }
  for (std::size_t k = 0; k < sc.charges.size(); ++k) {
    // Volume-weighted means over the deck's explosive blocks.
    double p = 0, vol0 = 0, vol = 0, burnt = 0;
    for (std::size_t i = 0; i < sc.block.size(); ++i) {
      if (sc.charge[i] != static_cast<std::int32_t>(k)) continue;
      p += sc.p[i] * sc.v0[i];
      vol0 += sc.v0[i];
      vol += sc.v[i] * sc.v0[i];
      burnt += sc.lambda[i] * sc.v0[i];
    }
    const GasBody& gs = sc.gas.bodies[k];
    if (gs.model == GasModel::Literal)
      std::fprintf(f, "%.9g,%s,%d,solid,%.9g,%.9g,%.9g,%.9g,%.9g,0,0,0,0\n", t,
                   sc.charges[k].hole.c_str(), sc.charges[k].deck + 1, p / vol0, vol / vol0,
                   burnt / vol0, vol, burnt * explosive_density(sc.eos[sc.charges[k].eos]));
    else
      std::fprintf(f, "%.9g,%s,%d,solid,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", t,
                   sc.charges[k].hole.c_str(), sc.charges[k].deck + 1, gs.pressure,
                   gs.v0 > 0 ? gs.volume() / gs.v0 : 1.0, burnt / vol0, gs.volume(),
                   gs.gas_mass() - gs.m_cracks, gs.m_cracks, gs.vented, gs.work, gs.plug_x);
  }
}

}  // namespace cdem
