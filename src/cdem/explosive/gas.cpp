#include "cdem/explosive/gas.hpp"

#include <algorithm>
#include <cmath>

namespace cdem {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

double choked_mass_flux(double p, double rho, double gamma) {
  if (!(p > 0) || !(rho > 0)) return 0.0;
  const double g = std::max(gamma, 1.0 + 1e-6);
  // rho* c* = rho c (2 / (g + 1))^((g + 1) / (2 (g - 1))), c = sqrt(g p / rho)
  return rho * std::sqrt(g * p / rho) * std::pow(2.0 / (g + 1.0), (g + 1.0) / (2.0 * (g - 1.0)));
}

double products_gamma(const Eos& eos, double v) {
  if (const auto* l = std::get_if<LandauEos>(&eos)) return v <= l->vc ? l->gamma1 : l->gamma2;
  const auto& j = std::get<JwlEos>(eos);
  return 1.0 + j.omega;
}

bool advance_plug(double& x, double& v, double p, double a, double c, double length, double mass,
                  double shear, double dt) {
  if (x >= length) return true;
  const double push = p * a, hold = shear * c * (length - x);
  if (v <= 0 && push <= hold) {  // static: friction holds it
    v = 0;
    return false;
  }
  const double acc = (push - hold) / mass;
  v = std::max(0.0, v + dt * acc);  // the wall friction cannot push it back in
  x += dt * v;
  return x >= length;
}

void update_deck_gas(Model& m, BarCharges& bc, AppliedLoads& out, double dt) {
  const std::size_t nbar = bc.bars.size();
  bool any = false;
  for (const auto& bar : bc.bars) any = any || bar.gas != GasModel::Literal;
  if (!any) return;
  std::vector<double>& scratch = bc.gas_scratch;  // per bar: burnt volume, cavity, crack volume, vent area
  scratch.assign(4 * nbar, 0.0);
  // 1. burnt charge and cavity volume per deck
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const auto b = bc.elem_block[i];
    double all = 0;
    for (auto e = bc.elem_bar_offset[i]; e < bc.elem_bar_offset[i + 1]; ++e) all += bc.elem_bar_vch[e];
    if (!(all > 0)) continue;
    // (a collapsed or inverted block holds no gas: J taken as 0 at most)
    const double dv = (std::max(m.vol_ratio[b], 0.0) - 1.0) * m.block_volume0[b];
    for (auto e = bc.elem_bar_offset[i]; e < bc.elem_bar_offset[i + 1]; ++e) {
      const auto k = bc.elem_bar[e];
      if (bc.bars[k].gas == GasModel::Literal) continue;
      // the element's burnt fraction for this bar: the mean of its segments of the bar
      double xi = 0;
      int n = 0;
      for (auto q = bc.elem_seg_offset[i]; q < bc.elem_seg_offset[i + 1]; ++q)
        if (bc.seg_bar[bc.elem_seg[q]] == k) xi += bc.seg_xi[bc.elem_seg[q]], ++n;
      xi = n ? xi / n : 0.0;
      const double vch = bc.elem_bar_vch[e];
      scratch[4 * k] += xi * vch;                               // burnt charge volume
      scratch[4 * k + 1] += xi * (vch + dv * vch / all);        // its cavity
    }
  }
  // 2. cracks: fill, volume, vents (the gas state of the last step sets the front speed)
  const int np = m.springs_per_iface;
  const bool cracks = [&] {
    for (const auto& bar : bc.bars)
      if (bar.gas == GasModel::Cracks) return true;
    return false;
  }();
  const std::size_t nlist = m.tied ? m.active_ifaces.size() : m.n_ifaces();
  auto iface_at = [&](std::size_t k) {
    return m.tied ? static_cast<std::size_t>(m.active_ifaces[k]) : k;
  };
  auto aperture = [&](std::size_t i) {
    double w = 0;
    const Vec3 n = m.iface_normal[i];
    for (int q = 0; q < np; ++q) w += dot(m.x[m.sp_b[i * np + q]] - m.x[m.sp_a[i * np + q]], n);
    return w / np;
  };
  auto open = [&](std::size_t i) {
    for (int q = 0; q < np; ++q) {
      const auto s = i * np + q;
      if (m.tied ? m.sp_tied[s] != 0 : m.sp_state[s] == kIntact) return false;
    }
    return true;
  };
  if (cracks) {
    for (std::size_t k = 0; k < nlist; ++k) {
      const std::size_t i = iface_at(k);
      if (!open(i)) continue;
      const auto ba = m.iface_block_a[i], bb = m.iface_block_b[i];
      std::int32_t d = bc.iface_deck[i];
      const double w = aperture(i);
      if (d < 0) {
        const std::int32_t da = bc.block_deck[ba], db = bc.block_deck[bb];
        d = da >= 0 ? da : db;
        if (d < 0 || bc.bars[d].gas != GasModel::Cracks || !(w > 0)) continue;
        bc.iface_deck[i] = d;
      }
      if (bc.bars[d].gas != GasModel::Cracks) continue;
      const auto& gs = bc.gas[d];
      const double mgas = gs.burnt - gs.vented;
      const double vol = gs.volume();
      if (bc.iface_fill[i] < 1.0f && mgas > 0 && vol > 0) {
        const double rho = mgas / vol;
        const double c = choked_mass_flux(gs.pressure, rho,
                                          products_gamma(bc.eos[bc.bars[d].eos], bc.bars[d].rho_w / rho)) /
                         rho;
        const double lc = 0.5 * (m.block_size[ba] + m.block_size[bb]);
        const double f = std::min(1.0, bc.iface_fill[i] + dt * c / lc);
        bc.iface_fill[i] = static_cast<float>(f);
        if (f >= 1.0) {
          if (bc.block_deck[ba] < 0) bc.block_deck[ba] = d;
          if (bc.block_deck[bb] < 0) bc.block_deck[bb] = d;
        }
      }
      if (w > 0) {
        const double area = np * m.sp_area.v[i];
        scratch[4 * d + 2] += bc.iface_fill[i] * area * w;
        if (bc.iface_fill[i] >= 1.0f && (bc.block_exterior[ba] || bc.block_exterior[bb]))
          scratch[4 * d + 3] += w * (m.dim == 3 ? std::sqrt(area) : 1.0);
      }
    }
  }
  // 3. per deck: pressure, plug, venting, work
  for (std::size_t k = 0; k < nbar; ++k) {
    const auto& bar = bc.bars[k];
    if (bar.gas == GasModel::Literal) continue;
    auto& gs = bc.gas[k];
    gs.burnt = bar.rho_w * scratch[4 * k];
    gs.v_cavity = scratch[4 * k + 1];
    gs.v_cracks = scratch[4 * k + 2];
    gs.section_plug = bar.section * std::min(gs.plug_x, bar.plug_length);
    const double vol = gs.volume();
    const double mgas = gs.burnt - gs.vented;
    double p = 0, rho = 0;
    if (mgas > 0 && vol > 0) {
      rho = mgas / vol;
      p = eos_pressure(bc.eos[bar.eos], bar.rho_w / rho);
    }
    gs.m_cracks = rho * gs.v_cracks;
    if (gs.v_prev > 0) gs.work += 0.5 * (p + gs.pressure) * (vol - gs.v_prev);
    gs.v_prev = vol;
    gs.pressure = p;
    // the plug
    if (bar.plug_length > 0 && !gs.plug_out && dt > 0) {
      const double perimeter = m.dim == 3 ? 2.0 * kPi * std::sqrt(bar.section / kPi) : 2.0;
      gs.plug_out = advance_plug(gs.plug_x, gs.plug_v, p, bar.section, perimeter, bar.plug_length,
                                 bar.plug_mass, bar.plug_shear, dt);
    }
    // vents: the collar (open from the start, or once the plug is out) and the cracks
    gs.vent_area = scratch[4 * k + 3] + ((bar.collar_open || gs.plug_out) ? bar.section : 0.0);
    if (gs.vent_area > 0 && mgas > 0 && dt > 0) {
      const double flux =
          bar.vent_cd * choked_mass_flux(p, rho, products_gamma(bc.eos[bar.eos], bar.rho_w / rho));
      gs.vented += std::min(flux * gs.vent_area * dt, 0.5 * mgas);  // explicit, at most half
    }
    // the segments' pressure: xi P (eq. 13 with the deck's common pressure)
    for (auto j = bar.seg_begin; j < bar.seg_end; ++j) {
      bc.seg_p[j] = bc.seg_xi[j] > 0 ? bc.seg_xi[j] * p : 0.0;
      bc.seg_v[j] = bar.v0 > 0 ? vol / bar.v0 : 1.0;
    }
  }
  // 4. the filled cracks' faces pushed apart by f P
  if (cracks) {
    for (std::size_t k = 0; k < nlist; ++k) {
      const std::size_t i = iface_at(k);
      const std::int32_t d = bc.iface_deck[i];
      bc.iface_gas_p[i] = 0.0f;
      if (d < 0 || bc.bars[d].gas != GasModel::Cracks || !open(i)) continue;
      const double w = aperture(i);
      if (!(w > 0)) continue;
      const double p = bc.iface_fill[i] * bc.gas[d].pressure;
      if (!(p > 0)) continue;
      bc.iface_gas_p[i] = static_cast<float>(p);
      const Vec3 f = (p * m.sp_area.v[i]) * m.iface_normal[i];  // on B's node, along n (A to B)
      for (int q = 0; q < np; ++q) {
        out.add(m, m.sp_b[i * np + q], f);
        out.add(m, m.sp_a[i * np + q], -1.0 * f);
      }
    }
  }
}

}  // namespace cdem
