#include "cdem/explosive/gas.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <exception>
#include <stdexcept>

#include "cdem/core/loop_split.hpp"
#include "cdem/core/prefetch.hpp"
#include "cdem/mesh/element_geometry.hpp"

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

// Does any gas body fill cracks (GasModel::Cracks)?
static bool fills_cracks(const GasField& g) {
  return std::any_of(g.bodies.begin(), g.bodies.end(), [](const GasBody& b) { return b.model == GasModel::Cracks; });
}

void init_gas_field(const Model& m, GasField& g, const std::vector<std::string>& closed_sets) {
  g.iface_fill.assign(m.n_ifaces(), 0.0f);
  g.iface_gas_p.assign(m.n_ifaces(), 0.0f);
  g.iface_body.assign(m.n_ifaces(), -1);
  g.iface_load.assign(m.n_ifaces(), -1);
  g.block_body.assign(m.n_blocks(), -1);
  g.block_exterior.assign(m.n_blocks(), 0);
  std::vector<int> closed(m.n_blocks(), 0);  // boundary faces of the block in closed sets
  for (const auto& name : closed_sets)
    if (const auto* set = m.facet_set(name))
      for (const auto& f : set->facets) ++closed[static_cast<std::size_t>(f.block)];
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    const int outer = local_faces(m.block_type[b]).count -
                      (m.block_iface_offset[b + 1] - m.block_iface_offset[b]);
    g.block_exterior[b] = outer > closed[b];
  }
  g.burnt_volume.assign(g.bodies.size(), 0.0);
  g.cavity.assign(g.bodies.size(), 0.0);
  // The crack pass's per-list arrays follow the list of opened interfaces, which grows during
  // the blast up to every interface: room for that now, so that no step allocates.
  const bool cracks = fills_cracks(g);
  if (cracks) {
    const std::size_t ni = m.n_ifaces();
    g.list_open.reserve(ni);
    g.list_aperture.reserve(ni);
    g.list_state.reserve(ni);
    g.list_body.reserve(ni);
    g.list_fill_area.reserve(ni);
    g.list_vent.reserve(ni);
    g.thread_loads.assign(static_cast<std::size_t>(omp_get_max_threads()) + 1, 0);
    g.load_power.reserve(ni * static_cast<std::size_t>(m.springs_per_iface));
  }
  g.scratch.assign(2 * g.bodies.size(), 0.0);
}

void seed_gas(const Model& m, GasField& g, std::int32_t b, std::int32_t k, bool wall) {
  if (g.block_body[b] < 0) g.block_body[b] = k;
  if (!wall) return;
  for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
    const std::int32_t code = m.block_iface_list[e];
    const std::size_t f = static_cast<std::size_t>(block_iface_index(code));
    const auto other = code > 0 ? m.iface_block_b[f] : m.iface_block_a[f];
    if (g.block_body[other] < 0) g.block_body[other] = k;
  }
}

namespace {

// The crack list of a step: the model's (tied mode its active interfaces, springs mode all), or
// the one given (its interfaces ascending, with their open flags and apertures).
struct ListView {
  const Model& m;
  const CrackInputs* given;
  std::size_t size() const {
    return given ? given->iface.size() : (m.tied ? m.active_ifaces.size() : m.n_ifaces());
  }
  std::size_t operator()(std::size_t k) const {
    return given ? static_cast<std::size_t>(given->iface[k])
                 : (m.tied ? static_cast<std::size_t>(m.active_ifaces[k]) : k);
  }
};

// (the interface k entries ahead in the list: its points' nodes and normal; `loads`: the nodes'
// velocities for the loads' power, else their positions for the apertures. The list is in
// ascending order (order_active_ifaces), but sparse early in a blast and its nodes scattered.)
void prefetch_ahead(const Model& m, const ListView& iface_at, std::int64_t k, bool loads) {
  const int np = m.springs_per_iface;
  const std::size_t i = iface_at(static_cast<std::size_t>(k));
  prefetch_at(i, m.iface_normal.data());
  if (!loads) prefetch_at(i * np, m.tied ? m.sp_tied.data() : m.sp_state.data());
  for (int q = 0; q < np; ++q) {
    const std::size_t s = i * np + q;
    if (loads) {
      prefetch_at(static_cast<std::size_t>(m.sp_b[s]), m.v.data());
      prefetch_at(static_cast<std::size_t>(m.sp_a[s]), m.v.data());
    } else {
      prefetch_at(static_cast<std::size_t>(m.sp_b[s]), m.x.data());
      prefetch_at(static_cast<std::size_t>(m.sp_a[s]), m.x.data());
    }
  }
}

}  // namespace

void update_gas(Model& m, GasField& g, const std::vector<Eos>& eos, AppliedLoads& out, double dt) {
  if (!g.any()) return;
  gas_state(m, g, eos, dt);
  gas_face_loads(m, g, out);
}

void gas_state(const Model& m, GasField& g, const std::vector<Eos>& eos, double dt, const CrackInputs* given) {
  const std::size_t nb = g.bodies.size();
  if (!g.any()) return;
  g.scratch.assign(2 * nb, 0.0);  // per body: crack volume, crack vent area (no reallocation)
  const int np = m.springs_per_iface;
  const bool cracks = fills_cracks(g);
  const ListView iface_at{m, given};
  const std::size_t nlist = iface_at.size();
  g.given_list = given != nullptr;
  // 1. cracks: which listed interfaces are open, their apertures, fill, volume, vents (the gas
  // state of the last step sets the front speed, the choked flux per density of each body:
  // computed once per body, the same value for all its cracks)
  if (cracks) {
    g.front_speed.assign(nb, 0.0);  // (no reallocation after the first step)
    for (std::size_t k = 0; k < nb; ++k) {
      const GasBody& gs = g.bodies[k];
      const double mgas = gs.gas_mass(), vol = gs.volume();
      if (gs.model != GasModel::Cracks || !(mgas > 0) || !(vol > 0)) continue;
      const double rho = mgas / vol;
      g.front_speed[k] = choked_mass_flux(gs.pressure, rho, products_gamma(eos[gs.eos], gs.rho_w / rho)) / rho;
    }
    // (a) In parallel, each interface on its own: whether it is open and its aperture (the
    // gathers of positions are most of this function's cost); for those whose gas body is known,
    // the fill of the crack front and their terms of the body's crack volume and vent area.
    // What an interface does here reads nothing another writes in this pass (the bodies, front
    // speeds and block sizes are fixed during it).
    // (b) Serially, in list order: the interfaces still without a body (they take it from their
    // blocks, which the fronts completed before them in the list have just reached), the
    // blocks reached by a completed front, and the sums. The same operations in the same order
    // as one serial pass: bitwise the same for any thread count.
    auto body_of = [&](std::int32_t d) -> const GasBody* {
      const GasBody& gs = g.bodies[d];
      return gs.model == GasModel::Cracks ? &gs : nullptr;
    };
    // the fill of interface i of body d (ba, bb its blocks), and whether it completed now
    auto advance_fill = [&](std::size_t i, std::int32_t d, std::int32_t ba, std::int32_t bb) {
      const GasBody& gs = g.bodies[d];
      const double mgas = gs.gas_mass(), vol = gs.volume();
      if (!(g.iface_fill[i] < 1.0f && mgas > 0 && vol > 0)) return false;
      const double c = g.front_speed[d];
      const double lc = 0.5 * (m.block_size[ba] + m.block_size[bb]);
      const double f = std::min(1.0, g.iface_fill[i] + dt * c / lc);
      g.iface_fill[i] = static_cast<float>(f);
      return f >= 1.0;
    };
    // the terms of an interface with aperture w > 0: fill x area (x w into the volume) and
    // its vent width (x w into the vent area; 0 when it does not vent)
    auto terms = [&](std::size_t i, std::int32_t ba, std::int32_t bb, std::size_t k) {
      const double area = np * m.sp_area.v[i];
      g.list_fill_area[k] = g.iface_fill[i] * area;
      g.list_vent[k] = g.iface_fill[i] >= 1.0f && (g.block_exterior[ba] || g.block_exterior[bb])
                           ? (m.dim == 3 ? std::sqrt(area) : 1.0)
                           : 0.0;
    };
    enum : std::uint8_t { kSkip = 0, kTerms = 1, kReached = 2, kSerial = 4 };
    g.list_open.resize(nlist);  // (within the room init_gas_field made)
    g.list_aperture.resize(nlist);
    g.list_state.resize(nlist);
    g.list_body.resize(nlist);
    g.list_fill_area.resize(nlist);
    g.list_vent.resize(nlist);
    static LoopSplit split_fill;
    const auto nl = static_cast<std::int64_t>(nlist);
    split_fill.run(nl, [&](const LoopSplit::Range& part) {
      for (std::int64_t k = part.lo; k < part.hi; ++k) {
        // (the interface's own data 2 x kPrefetchAhead entries ahead, its blocks' kPrefetchAhead)
        if (k + 2 * kPrefetchAhead < nl) {
          const std::size_t ia = iface_at(static_cast<std::size_t>(k + 2 * kPrefetchAhead));
          prefetch_at(ia, m.iface_block_a.data(), m.iface_block_b.data(), g.iface_body.data(), m.sp_area.v.data());
          prefetch_for_write_at(ia, g.iface_fill.data());
        }
        if (k + kPrefetchAhead < nl && !given) {
          prefetch_ahead(m, iface_at, k + kPrefetchAhead, false);
          const std::size_t ia = iface_at(static_cast<std::size_t>(k + kPrefetchAhead));
          for (const auto blk : {m.iface_block_a[ia], m.iface_block_b[ia]})
            prefetch_at(static_cast<std::size_t>(blk), g.block_exterior.data(), m.block_size.data());
        }
        const std::size_t i = iface_at(static_cast<std::size_t>(k));
        const bool is_open = given ? given->open[static_cast<std::size_t>(k)] != 0 : crack_open(m, i);
        g.list_open[k] = is_open;
        g.list_aperture[k] = is_open ? (given ? given->aperture[static_cast<std::size_t>(k)] : crack_aperture(m, i)) : 0.0;
        std::uint8_t st = kSkip;
        if (is_open) {
          const std::int32_t d = g.iface_body[i];
          if (d < 0) {
            st = kSerial;
          } else if (body_of(d)) {
            const auto ba = m.iface_block_a[i], bb = m.iface_block_b[i];
            if (advance_fill(i, d, ba, bb)) st |= kReached;
            if (g.list_aperture[k] > 0) {
              terms(i, ba, bb, static_cast<std::size_t>(k));
              st |= kTerms;
            }
            g.list_body[k] = d;
          }
        }
        g.list_state[k] = st;
      }
    });
    g.reached_now.clear();
    g.chain_overflow = -1;
    for (std::size_t k = 0; k < nlist; ++k) {
      std::uint8_t st = g.list_state[k];
      if (st == kSkip) continue;
      const double w = g.list_aperture[k];
      std::int32_t d = g.list_body[k];
      std::int32_t source = -1;  // (the block a crack without gas takes its gas from)
      if (st & kSerial) {
        const std::size_t i = iface_at(k);
        const auto ba = m.iface_block_a[i], bb = m.iface_block_b[i];
        const std::int32_t da = g.block_body[ba], db = g.block_body[bb];
        d = da >= 0 ? da : db;
        source = da >= 0 ? ba : bb;
        if (d < 0 || !body_of(d) || !(w > 0)) continue;
        g.iface_body[i] = d;
        st = advance_fill(i, d, ba, bb) ? kReached : kSkip;
        terms(i, ba, bb, k);
        st |= kTerms | kSerial;
      }
      if (st & kReached) {
        const std::size_t i = iface_at(k);
        const auto ba = m.iface_block_a[i], bb = m.iface_block_b[i];
        // (a given list: a crack that filled in the step its gas reached it, from a block reached
        // in this pass, puts the front further from the step's start than the list's rule sees:
        // CrackInputs)
        if (given && (st & kSerial) &&
            std::find(g.reached_now.begin(), g.reached_now.end(), source) != g.reached_now.end())
          g.chain_overflow = static_cast<std::int32_t>(i);
        for (const auto blk : {ba, bb})
          if (g.block_body[blk] < 0) {
            g.block_body[blk] = d;
            if (given) g.reached_now.push_back(blk);
          }
      }
      if (st & kTerms) {
        g.scratch[2 * d] += g.list_fill_area[k] * w;
        if (g.list_vent[k] != 0) g.scratch[2 * d + 1] += w * g.list_vent[k];
      }
    }
  }
  // 2. per body: pressure, plug, venting, work
  for (std::size_t k = 0; k < nb; ++k) {
    GasBody& gs = g.bodies[k];
    if (gs.model == GasModel::Literal) continue;
    const double burnt_before = gs.burnt;
    gs.burnt = gs.rho_w * g.burnt_volume[k];
    gs.v_cavity = std::max(g.cavity[k], 0.0);
    gs.v_cracks = g.scratch[2 * k];
    gs.v_plug = gs.section * std::min(gs.plug_x, gs.plug_length);
    const double vol = gs.volume(), mgas = gs.gas_mass();
    double p = 0, rho = 0;
    if (mgas > 0 && vol > 0) {
      rho = mgas / vol;
      p = eos_pressure(eos[gs.eos], gs.rho_w / rho);
    }
    gs.m_cracks = rho * gs.v_cracks;
    // The products' expansion work: the volume's growth less the volume the charge burnt this
    // step brings (its products start at the explosive's density, doing no work to get there).
    if (gs.v_prev > 0)
      gs.work += 0.5 * (p + gs.pressure) * ((vol - gs.v_prev) - (gs.burnt - burnt_before) / gs.rho_w);
    gs.v_prev = vol;
    gs.pressure = p;
    if (gs.plug_length > 0 && !gs.plug_out && dt > 0) {
      const double perimeter = m.dim == 3 ? 2.0 * kPi * std::sqrt(gs.section / kPi) : 2.0;
      gs.plug_out = advance_plug(gs.plug_x, gs.plug_v, p, gs.section, perimeter, gs.plug_length,
                                 gs.plug_mass, gs.plug_shear, dt);
    }
    gs.vent_area = g.scratch[2 * k + 1] + ((gs.collar_open || gs.plug_out) ? gs.section : 0.0);
    if (gs.vent_area > 0 && mgas > 0 && dt > 0) {
      const double flux = gs.vent_cd * choked_mass_flux(p, rho, products_gamma(eos[gs.eos], gs.rho_w / rho));
      gs.vented += std::min(flux * gs.vent_area * dt, 0.5 * mgas);  // explicit, at most half
      // the state after this step's venting (one density for the cavity and the cracks)
      const double m_after = gs.gas_mass();
      rho = m_after / vol;
      gs.pressure = m_after > 0 ? eos_pressure(eos[gs.eos], gs.rho_w / rho) : 0.0;
      gs.m_cracks = rho * gs.v_cracks;
    }
  }
}

void gas_face_loads(Model& m, GasField& g, AppliedLoads& out) {
  if (!g.any()) return;
  if (g.given_list) throw std::logic_error("gas_face_loads: the step's list was given (a part applies its own loads)");
  const int np = m.springs_per_iface;
  const bool cracks = fills_cracks(g);
  const ListView iface_at{m, nullptr};
  const std::size_t nlist = iface_at.size();
  // 3. the filled cracks' faces pushed apart by f P, in one parallel region: each thread forms
  // the pressures of its contiguous range of the list (into the apertures' array, no longer
  // needed) and counts its loads; their places in the record follow in list order (the threads'
  // counts summed in thread order, which is list order); then each thread writes its range's
  // loads and their power terms at those places. Then the forces added per block in parallel,
  // each node's in record order, and the power terms summed in record order, serially (below:
  // the same sums, in the same order, as adding the loads one by one, bitwise the same for any
  // thread count).
  if (cracks) {
    const auto nl = static_cast<std::int64_t>(nlist);
    if (const auto want = static_cast<std::size_t>(omp_get_max_threads()) + 1; g.thread_loads.size() < want)
      g.thread_loads.assign(want, 0);  // (the thread count grew: rare)
    static LoopSplit split_loads;
    std::size_t first = 0;
    std::int64_t nload = 0;
    std::exception_ptr failed;
#pragma omp parallel
    {
      const LoopSplit::Range part = split_loads.begin(nl);
      std::int64_t mine = 0;
      for (std::int64_t k = part.lo; k < part.hi; ++k) {
        const std::size_t i = iface_at(static_cast<std::size_t>(k));
        const std::int32_t d = g.iface_body[i];
        double p = 0;
        if (d >= 0 && g.bodies[d].model == GasModel::Cracks && g.list_open[k] && g.list_aperture[k] > 0)
          p = g.iface_fill[i] * g.bodies[d].pressure;
        if (!(p > 0)) p = 0;
        g.iface_gas_p[i] = static_cast<float>(p);
        g.list_aperture[k] = p;
        if (p > 0) mine += np;
      }
      g.thread_loads[static_cast<std::size_t>(part.thread) + 1] = mine;
      const double first_half = omp_get_wtime() - part.t0;  // (the thread's work, not the wait)
#pragma omp barrier
#pragma omp single
      {
        g.thread_loads[0] = 0;
        for (int t = 0; t < part.threads; ++t) g.thread_loads[t + 1] += g.thread_loads[t];
        nload = g.thread_loads[static_cast<std::size_t>(part.threads)];
        try {  // (growing the record allocates at the first steps; an exception must not leave the region)
          first = out.append_pairs(static_cast<std::size_t>(nload));
          g.load_power.resize(static_cast<std::size_t>(nload));  // (within the room init_gas_field made)
        } catch (...) {
          failed = std::current_exception();
        }
      }
      const double t_second = omp_get_wtime();
      std::int64_t r = g.thread_loads[static_cast<std::size_t>(part.thread)];
      for (std::int64_t k = part.lo; k < part.hi && !failed; ++k) {
        if (k + kPrefetchAhead < part.hi && g.list_aperture[k + kPrefetchAhead] > 0)
          prefetch_ahead(m, iface_at, k + kPrefetchAhead, true);
        const double p = g.list_aperture[k];
        const std::size_t i = iface_at(static_cast<std::size_t>(k));
        g.iface_load[i] = p > 0 ? static_cast<std::int32_t>(r) : -1;
        if (!(p > 0)) continue;
        const Vec3 f = (p * m.sp_area.v[i]) * m.iface_normal[i];  // on B's node, along n (A to B)
        for (int q = 0; q < np; ++q) {
          const auto rq = static_cast<std::size_t>(r + q);
          const std::int32_t b = m.sp_b[i * np + q], a = m.sp_a[i * np + q];
          out.pair_b[first + rq] = b;
          out.pair_a[first + rq] = a;
          out.pair_force[first + rq] = f;
          g.load_power[rq] = dot(f, m.v[b] - m.v[a]);
        }
        r += np;
      }
      split_loads.record(part.thread, part.threads, first_half + (omp_get_wtime() - t_second));
    }
    split_loads.update();
    if (failed) std::rethrow_exception(failed);
    // The forces: per block in parallel, each node's loads in the record's order (its block's
    // loaded interfaces sorted by their places in the record, whatever the list's order), so
    // each node's sum is the one adding the record in order gives, bit for bit (each node is
    // one block's); then the power terms in order.
    static LoopSplit split_apply;
    const auto nbk = static_cast<std::int64_t>(m.n_blocks());
    const Vec3* const force = out.pair_force.data() + first;
    split_apply.run(nbk, [&](const LoopSplit::Range& part) {
      for (std::int64_t b = part.lo; b < part.hi; ++b) {
        if (m.tied && !m.block_active[b]) continue;  // (no opened interface: no crack face)
        // its loaded interfaces (a block has at most 4 faces): record place, side code
        std::array<std::pair<std::int32_t, std::int32_t>, 4> mine;
        int nmine = 0;
        for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
          const std::int32_t code = m.block_iface_list[e];
          const std::int32_t r = g.iface_load[static_cast<std::size_t>(block_iface_index(code))];
          if (r < 0) continue;
          assert(nmine < 4 && "a block with more than 4 faces");  // (tri, quad, tet: at most 4)
          mine[nmine++] = {r, code};
        }
        std::sort(mine.begin(), mine.begin() + nmine);
        for (int j = 0; j < nmine; ++j) {
          const auto [r, code] = mine[j];
          const auto i = static_cast<std::size_t>(block_iface_index(code));
          if (code > 0) {  // the block is A's side: -f
            for (int q = 0; q < np; ++q) m.f[m.sp_a[i * np + q]] -= force[r + q];
          } else {
            for (int q = 0; q < np; ++q) m.f[m.sp_b[i * np + q]] += force[r + q];
          }
        }
      }
    });
    out.book_pair_power(static_cast<std::size_t>(nload), g.load_power.data());
  }
}

bool gas_candidate(const Model& m, const GasField& g, std::size_t i, bool open, double aperture) {
  if (!open) return false;
  if (g.iface_body[i] >= 0) return true;
  if (!(aperture > 0)) return false;
  for (const auto b : {m.iface_block_a[i], m.iface_block_b[i]}) {
    if (g.block_body[b] >= 0) return true;
    for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
      const std::int32_t code = m.block_iface_list[e];
      const auto f = static_cast<std::size_t>(block_iface_index(code));
      const auto other = code > 0 ? m.iface_block_b[f] : m.iface_block_a[f];
      if (g.iface_body[f] >= 0 || g.block_body[other] >= 0) return true;
    }
  }
  return false;
}

}  // namespace cdem
