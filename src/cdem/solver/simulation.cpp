#include "cdem/solver/simulation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "cdem/core/error.hpp"
#include "cdem/core/exact_sum.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/physics/block_forces.hpp"
#include "cdem/physics/integrate.hpp"
#include "cdem/physics/springs.hpp"
#include "cdem/physics/stiffness_damping.hpp"
#include "cdem/physics/tie_failure.hpp"
#include "cdem/physics/ties.hpp"
#include "cdem/solver/run_state.hpp"

namespace cdem {

Simulation::Simulation(Model model, const Case& c, const WholeModelSetup* whole) : m_(std::move(model)) {
  m_.release_distance_factor = c.release_distance_factor;
  // (180: never, not cos 180 = -1, which rounding can pass for faces facing exactly opposite)
  const double angle = release_angle_of(c);
  m_.release_cos = angle >= 180.0 ? -std::numeric_limits<double>::infinity()
                                  : std::cos(angle * std::numbers::pi / 180.0);
  bc_ = prepare_boundaries(m_, c.boundaries, c.gravity, c.path);
  if (whole && !whole->damping.empty())
    m_.damping = whole->damping;
  else
    setup_damping_zones(c);
  // after the zones: an undamped model drops its damping arrays (a part those the whole drops)
  if (!whole) {
    release_zero_damping(m_);
  } else {
    if (whole->damping.empty()) std::vector<double>().swap(m_.damping);
    if (!whole->local_damping) std::vector<double>().swap(m_.local_damping);
  }
  std::vector<double>().swap(m_.inv_mass);  // no kernel reads it (integrate uses mass)
  release_unused_spring_state(m_);  // no fracture-energy law: sp_w, sp_slip, sp_dil dropped
  for (const auto& f : c.analysis.main_faces)
    if (!m_.facet_set(f))
      throw InputError(fmt::format("{}: key 'analysis.main_faces': no face set '{}' in the mesh", c.path, f));
  setup_initial_stress(c);
  // Without an in-situ stress stress0 is zero everywhere: released (the block kernels read a
  // zero then).
  {
    bool zero = true;
    for (const auto& s0 : m_.stress0)
      for (double v : s0) zero = zero && v == 0;
    if (zero) std::vector<Sym6>().swap(m_.stress0);
  }
  if (c.interface_mode == InterfaceMode::Tied) {
    // (before the ties: build_ties averages the clusters' initial velocities with the masses)
    if (c.mass_scaling_dt > 0) {
      // the element bound whose step (x safety / sqrt(1 + eta), as below) is the one asked
      const double bound = c.mass_scaling_dt * std::sqrt(1.0 + c.opened_stiffness) / c.dt_safety;
      if (!std::isfinite(bound) || !(4.0 / (bound * bound) > 0))
        throw InputError(fmt::format("{}: key 'simulation.mass_scaling_dt': {:g} s is not a time step "
                                     "(expected at most about the run's length)",
                                     c.path, c.mass_scaling_dt));
      mass_scaling_ = scale_masses_to_bound(m_, bound);
      if (mass_scaling_.share() > c.mass_scaling_limit)
        throw InputError(fmt::format(
            "{}: key 'simulation.mass_scaling_dt': a step of {:g} s needs {:.4g} kg more mass on {} "
            "blocks (up to {:.3g} times their own), {:.3g} of the model's {:.6g} kg: above "
            "simulation.mass_scaling_limit = {:g}. Ask a smaller step, raise the limit, or mesh "
            "with fewer small or flat elements",
            c.path, c.mass_scaling_dt, mass_scaling_.added, mass_scaling_.blocks,
            mass_scaling_.max_factor, mass_scaling_.share(), mass_scaling_.total,
            c.mass_scaling_limit));
    }
    build_ties(m_);
    // (a part: the whole model's step and largest frequency, not its subset's: not computed)
    if (whole && whole->stable)
      stable_ = *whole->stable;
    else
      stable_ = stable_time_step_tied(m_, c.dt_safety, c.opened_stiffness, &omega2_max_);
    if (whole) omega2_max_ = whole->omega2_max;
    opened_ = set_opened_stiffness(m_, c.opened_stiffness, omega2_max_,
                                   whole && !whole->node_springs.empty() ? &whole->node_springs : nullptr);
    const std::size_t nv = m_.n_vertices();
    vtx_ke_.assign(nv, 0.0);
    vtx_reaction_.assign(2 * nv, 0.0);
    vtx_con_.assign(nv, 0);
    for (const auto& cn : bc_.constraints) vtx_con_[m_.node_vertex[cn.node]] = 1;
    for (std::size_t v = 0; v < nv; ++v)
      if (vtx_con_[v]) con_vertices_.push_back(static_cast<std::int32_t>(v));
    if (!m_.damping.empty() || !m_.local_damping.empty()) vtx_dissipated_.assign(nv, 0.0);
    if (!m_.damping.empty() || !m_.local_damping.empty()) vtx_cke_.assign(nv, 0.0);
    tie_flag_.assign(m_.n_ifaces(), 0);
  } else {
    stable_ = whole && whole->stable ? *whole->stable : stable_time_step(m_, c.dt_safety, c.contact.enabled);
  }
  contact_ = setup_contact(m_, c.contact, c.opened_stiffness, m_.tied ? omega2_max_ : 0.0);
  beta_max_ = max_stiffness_damping(m_);
  if (beta_max_ > 0) {
    if (!(whole && whole->stable)) {  // (the whole model's is damped already)
      stable_.dt = stable_.safety * damped_stable_step(stable_.dt / stable_.safety, beta_max_);
      stable_.limit += " with stiffness damping";
    }
    sd_force_.assign(m_.n_nodes(), Vec3{});
    sd_power_.assign(m_.n_blocks(), 0.0);
  }
  fixed_dt_ = c.fixed_dt;
  case_path_ = c.path;
  dt_ = stable_.dt;
  if (c.fixed_dt > 0) {
    if (c.fixed_dt > stable_.dt / c.dt_safety)
      throw InputError(fmt::format("{}: key 'simulation.dt': {} s is above the stable step {:.4g} s "
                                   "(limited by the {})",
                                   c.path, c.fixed_dt, stable_.dt / c.dt_safety, stable_.limit));
    dt_ = c.fixed_dt;
  }
  if (!(dt_ > 0) || !std::isfinite(dt_))
    throw InputError(fmt::format("{}: no finite stable time step (a model without blocks?)", c.path));
  // Per block (integrate.hpp); the dissipation and c ke only for a damped model.
  const bool damped = !m_.damping.empty() || !m_.local_damping.empty();
  if (!m_.tied) {  // (tied mode: per vertex, above)
    if (damped) block_dissipated_.assign(m_.n_blocks(), 0.0);
    if (damped) cke_.assign(m_.n_blocks(), 0.0);
    ke_.assign(m_.n_blocks(), 0.0);
  }
  // Forces at t = 0 (block stresses for output before the first step).
  block_forces(m_, nullptr);
  // An initial velocity field counts as initial (kinetic) energy.
  for (std::size_t b = 0; b < ke_.size(); ++b)
    for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n)
      ke_[b] += 0.5 * m_.mass[n] * dot(m_.v[n], m_.v[n]);
  for (std::size_t v = 0; v < vtx_ke_.size(); ++v)
    for (auto k = m_.vtx_offset[v]; k < m_.vtx_offset[v + 1]; ++k) {
      const auto n = m_.vtx_nodes[k];
      vtx_ke_[v] += 0.5 * m_.mass[n] * dot(m_.v[n], m_.v[n]);
    }
  e_initial_ = energy().mechanical();
}

void Simulation::limit_dt(double dt_max, const std::string& what) {
  if (!(dt_max > 0) || !std::isfinite(dt_max)) return;
  dt_max = damped_stable_step(dt_max, beta_max_);
  if (fixed_dt_ > 0) {
    if (fixed_dt_ > dt_max)
      throw InputError(fmt::format("{}: key 'simulation.dt': {} s is above the stable step {:.4g} s "
                                   "of the {}",
                                   case_path_, fixed_dt_, dt_max, what));
    return;
  }
  const double safety = stable_.safety;
  if (safety * dt_max < dt_) {
    dt_ = safety * dt_max;
    stable_.dt = dt_;
    stable_.limit = beta_max_ > 0 ? what + " with stiffness damping" : what;
  }
}

void Simulation::setup_damping_zones(const Case& c) {
  for (std::size_t zi = 0; zi < c.damping_zones.size(); ++zi) {
    const auto& z = c.damping_zones[zi];
    int region = -1;
    std::string names;
    for (std::size_t r = 0; r < m_.region_names.size(); ++r) {
      if (m_.region_names[r] == z.region) region = static_cast<int>(r);
      names += (names.empty() ? "'" : ", '") + m_.region_names[r] + "'";
    }
    if (region < 0)
      throw InputError(fmt::format("{}: key 'damping_zone[{}].region': region '{}' is not in the "
                                   "mesh (its regions are {})",
                                   c.path, zi, z.region, names));
    // Inner edge: vertices the zone shares with blocks outside it.
    std::vector<char> in_zone(m_.n_blocks(), 0), out_vertex, in_vertex;
    std::int32_t nv = 0;
    for (auto v : m_.node_vertex) nv = std::max(nv, v + 1);
    out_vertex.assign(nv, 0);
    in_vertex.assign(nv, 0);
    for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
      in_zone[b] = m_.block_region[b] == region;
      for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n)
        (in_zone[b] ? in_vertex : out_vertex)[m_.node_vertex[n]] = 1;
    }
    std::vector<Vec3> edge;
    std::vector<char> seen(nv, 0);
    for (std::size_t n = 0; n < m_.n_nodes(); ++n) {
      const auto v = m_.node_vertex[n];
      if (in_vertex[v] && out_vertex[v] && !seen[v]) {
        seen[v] = 1;
        edge.push_back(m_.X(n));
      }
    }
    std::vector<double> dist(m_.n_blocks(), 0.0);
    double dmax = 0;
    for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
      if (!in_zone[b]) continue;
      Vec3 cen{};
      const auto n0 = m_.block_first_node[b], n1 = m_.block_first_node[b + 1];
      for (auto n = n0; n < n1; ++n) cen += m_.X(n);
      cen = cen / (n1 - n0);
      double d = edge.empty() ? 0.0 : std::numeric_limits<double>::infinity();
      for (const auto& p : edge) d = std::min(d, norm(cen - p));
      dist[b] = d;
      dmax = std::max(dmax, d);
    }
    for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
      if (!in_zone[b]) continue;
      // Graded from zero at the inner edge to max_damping at the outer edge.
      const double mu = dmax > 0 ? z.max_damping * std::pow(dist[b] / dmax, z.exponent) : z.max_damping;
      for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n) m_.damping[n] += mu;
    }
  }
}

void Simulation::setup_initial_stress(const Case& c) {
  if (!c.initial_stress.enabled) return;
  const auto& is = c.initial_stress;
  auto stress_at = [&](Vec3 p) {
    const double depth = is.reference_level - (m_.dim == 3 ? p.z : p.y);
    Sym6 s;
    for (int k = 0; k < 6; ++k) s[k] = is.at_reference[k] + is.gradient[k] * depth;
    return s;
  };
  std::vector<Vec3> centroid(m_.n_blocks());
  for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
    Vec3 cen{};
    const auto n0 = m_.block_first_node[b], n1 = m_.block_first_node[b + 1];
    for (auto n = n0; n < n1; ++n) cen += m_.X(n);
    centroid[b] = cen / (n1 - n0);
    m_.stress0[b] = stress_at(centroid[b]);
    m_.stress[b] = m_.stress0[b];
  }
  // Pre-load the springs with the traction of the mean stress of their two blocks (springs
  // mode; a tie carries it through the blocks' stress).
  if (c.interface_mode == InterfaceMode::Tied) return;
  const int np = m_.springs_per_iface;
  m_.sp_g0.assign(m_.n_springs(), 0.0);
  for (std::size_t i = 0; i < m_.n_ifaces(); ++i) {
    const Sym6 sa = m_.stress0[m_.iface_block_a[i]], sb = m_.stress0[m_.iface_block_b[i]];
    Sym6 s;
    for (int k = 0; k < 6; ++k) s[k] = 0.5 * (sa[k] + sb[k]);
    Vec3 pa[3];
    for (int q = 0; q < np; ++q) pa[q] = m_.X(m_.sp_a[i * np + q]);
    Vec3 n{};
    if (np == 2) {
      const Vec3 t = pa[1] - pa[0];
      n = normalized(Vec3{t.y, -t.x, 0});
    } else {
      n = normalized(cross(pa[1] - pa[0], pa[2] - pa[0]));
    }
    const Vec3 tr{s[0] * n.x + s[3] * n.y + s[5] * n.z, s[3] * n.x + s[1] * n.y + s[4] * n.z,
                  s[5] * n.x + s[4] * n.y + s[2] * n.z};
    const double sn = dot(tr, n);
    for (int q = 0; q < np; ++q) {
      const auto sp = i * np + q;
      m_.sp_fn[sp] = sn * m_.sp_area[sp];
      m_.sp_g0[sp] = m_.sp_fn[sp] / m_.sp_kn[sp];  // F_n = k_n A_c (d_n + g0) = F_n0 at d_n = 0
      m_.sp_fs[sp] = m_.sp_area[sp] * (tr - sn * n);
    }
  }
}

void Simulation::step(bool sample) {
  double clock = timer_ ? omp_get_wtime() : 0.0;
  auto lap = [&](StepKernel k) {
    if (!timer_) return;
    const double now = omp_get_wtime();
    timer_->s[k] += now - clock;
    clock = now;
  };
  // 0. tied mode: the interfaces activated since the last step merged into the ascending list
  if (m_.tied) order_active_ifaces(m_);
  // 1. positions x(n) = x(n-1) + dt v(n-1/2)
  update_positions(m_, dt_);
  lap(kStepPositions);
  // 2. spring forces (on x(n), independent of the block forces; tied mode: untied points only);
  // in a distributed run this rank's share, then shared with the other ranks
  const std::int64_t released_before = m_.released_points;
  const auto [s_lo, s_hi] = spring_share();
  spring_forces(m_, dt_, t_, s_lo, s_hi);
  if (!rank_blocks_.empty()) share_springs(released_before);
  lap(kStepSprings);
  // 3. block forces (assign f), each block adding its nodes' spring forces right after; in a
  // distributed run this rank's blocks, then shared with the other ranks
  std::int32_t first = -1;
  auto inv = block_forces(m_, &first, /*gather_springs=*/true, own_lo_, own_hi_);
  if (!rank_blocks_.empty()) inv = share_blocks(inv);
  if (halo_) {
    part_inverted(inv, first);  // a part: its own blocks (over the whole model in step_sums)
  } else if (inv > 0) {
    // only the rock's inversions stop a run (rock_inverted): recounted here, in the rare steps
    // with an inversion
    inv = 0;
    first = -1;
    for (std::size_t b = 0; b < m_.n_blocks(); ++b)
      if (rock_inverted(b)) {
        if (first < 0) first = static_cast<std::int32_t>(b);
        ++inv;
      }
  }
  // 3b. stiffness-proportional damping of the blocks (when a material has it)
  if (beta_max_ > 0) stiffness_damping_forces(m_, sd_force_, sd_power_);
  lap(kStepBlocks);
  // 4. general contact between fragments, released faces and boundary faces
  contact_forces(m_, contact_, dt_);
  if (contact_.max_pen_at.fresh) contact_.max_pen_at.time = t_, contact_.max_pen_at.fresh = false;
  lap(kStepContact);
  // 5. explosive and other loads (a charge's blocks get their total stress: the products'
  // pressure included)
  applied_.clear();
  for (auto& h : loads_) h(m_, applied_, t_);
  lap(kStepLoads);
  // 6. tied mode: ties broken by the blocks' traction are untied (their force added to f)
  if (m_.tied) tie_failure(m_, t_, tie_flag_, &insert_terms_);
  lap(kStepTies);
  // 7. boundary loads (pressure, dashpots)
  boundary_forces(m_, bc_, t_);
  lap(kStepBoundary);
  // 8. integration with gravity and damping, then the velocity constraints (prescribed at the
  // mid-step time); tied mode: one velocity per cluster, constrained as a whole.
  if (m_.tied) {
    integrate_tied(m_, bc_, dt_, t_ + 0.5 * dt_, vtx_con_.data(), vtx_dissipated_.data(),
                   sample ? vtx_ke_.data() : nullptr, vtx_cke_.empty() ? nullptr : vtx_cke_.data(),
                   vtx_reaction_.data());
    lap(kStepIntegrate);
  } else {
    integrate(m_, bc_.gravity, dt_, block_dissipated_.data(), sample ? ke_.data() : nullptr,
              cke_.empty() ? nullptr : cke_.data());
    lap(kStepIntegrate);
    apply_constraints(m_, bc_, t_ + 0.5 * dt_, dt_, con_terms_);
  }
  // 9. the works of the step, F(n) . (v(n-1/2) + v(n+1/2)) / 2 dt, and their parts after t_n
  // (energy() takes those back out, see last_*_)
  load_work_terms(m_, bc_);
  if (!halo_) applied_.now_terms(m_);
  step_sums(inv, first);
  t_ += dt_;
  ++steps_;
  lap(kStepWork);
}

void Simulation::step_sums(std::int64_t inv, std::int32_t first) {
  // Each term once, summed exactly (core/exact_sum.hpp): the same bits in any order, and in a
  // part (the halo stage) over its own entities with the sums reduced over the ranks, so that
  // every rank gets the whole model's sums, the bits one process gets.
  enum : std::size_t {
    kReaction, kReactionAfter,    // tied: the constrained vertices' reaction works; springs: powers
    kLoad, kLoadAfter, kAbsorbed, kAbsorbedAfter,  // the boundary loads' powers (load_work_terms)
    kInsertion, kExplosiveOld, kExplosiveNew,
    kStiffOld, kStiffNew,  // the stiffness damping's power with v(n-1/2) (per block) and v(n+1/2)
    kInverted, kSums
  };
  const OwnMasks own = own_masks();
  constexpr auto mine = &OwnMasks::mine;
  const std::vector<double> sum = sum_exactly(kSums, [&](auto&& put) {
    if (m_.tied) {
      for (auto v : con_vertices_)
        if (mine(own.vertex, static_cast<std::size_t>(v))) {
          put(kReaction, vtx_reaction_[2 * static_cast<std::size_t>(v)]);
          put(kReactionAfter, vtx_reaction_[2 * static_cast<std::size_t>(v) + 1]);
        }
    } else {
      for (std::size_t j = 0; j < bc_.constraints.size(); ++j)
        if (mine(own.node, static_cast<std::size_t>(bc_.constraints[j].node))) {
          put(kReaction, con_terms_[2 * j]);
          put(kReactionAfter, con_terms_[2 * j + 1]);
        }
    }
    const double* wt = bc_.work_terms.data();
    for (std::size_t i = 0; i < bc_.work_nodes.size(); ++i)
      if (mine(own.node, static_cast<std::size_t>(bc_.work_nodes[i]))) {
        put(kLoad, wt[4 * i]);
        put(kAbsorbed, wt[4 * i + 1]);
        put(kLoadAfter, wt[4 * i + 2]);
        put(kAbsorbedAfter, wt[4 * i + 3]);
      }
    const auto np = static_cast<std::int64_t>(m_.springs_per_iface);
    for (const auto& [s, e] : insert_terms_)
      if (mine(own.iface, static_cast<std::size_t>(s / np))) put(kInsertion, e);
    if (halo_) {  // (a part's loads: those it owns, AppliedLoads::Owned)
      const AppliedLoads::Owned& xo = applied_.owned;
      for (std::size_t k = 0; k < xo.b.size(); ++k) {
        const auto b = static_cast<std::size_t>(xo.b[k]);
        put(kExplosiveOld, xo.old[k]);
        put(kExplosiveNew, xo.a[k] < 0 ? dot(xo.f[k], m_.v[b]) : dot(xo.f[k], m_.v[b] - m_.v[static_cast<std::size_t>(xo.a[k])]));
      }
    } else {
      for (double p : applied_.old_terms) put(kExplosiveOld, p);
      const std::size_t nx = applied_.node.size() + applied_.pair_b.size();
      for (std::size_t k = 0; k < nx; ++k) put(kExplosiveNew, applied_.terms[k]);
    }
    if (beta_max_ > 0) {
      for (std::size_t b = 0; b < sd_power_.size(); ++b)
        if (mine(own.block, b)) put(kStiffOld, sd_power_[b]);
      for (std::size_t n = 0; n < sd_force_.size(); ++n)
        if (mine(own.node, n)) put(kStiffNew, dot(sd_force_[n], m_.v[n]));
    }
    put(kInverted, static_cast<double>(inv));  // (a count below 2^53: exact)
  }, halo_ ? rank_reducer() : nullptr);
  const double half = 0.5 * dt_;
  // tied mode: the reactions' terms are works (integrate_tied); springs mode: powers
  const double react = m_.tied ? 1.0 : dt_, react_after = m_.tied ? 1.0 : half;
  w_boundary_ += react * sum[kReaction] + dt_ * sum[kLoad];
  last_boundary_ = react_after * sum[kReactionAfter] + half * sum[kLoadAfter];
  w_absorbed_ -= dt_ * sum[kAbsorbed];
  last_absorbed_ = -half * sum[kAbsorbedAfter];
  w_insert_ += sum[kInsertion];
  w_explosive_ += half * (sum[kExplosiveOld] + sum[kExplosiveNew]);
  last_explosive_ = half * sum[kExplosiveNew];
  // (every rank: a part without a damped block lists no terms, but the sums are the whole's)
  w_sdamp_ += half * (sum[kStiffOld] + sum[kStiffNew]);
  last_sdamp_ = half * sum[kStiffNew];
  inverted_ = static_cast<std::int64_t>(sum[kInverted]);
  // the first inverted block (the whole model's index): the least over the ranks
  if (halo_ && inverted_ > 0) {
    constexpr std::int64_t none = std::numeric_limits<std::int64_t>::min();
    const std::int64_t r = max_over_ranks(first >= 0 ? -static_cast<std::int64_t>(first) : none);
    first = r == none ? -1 : static_cast<std::int32_t>(-r);
  }
  if (inverted_ > 0 && first_inverted_ < 0) first_inverted_ = first;
}

void Simulation::distribute(const std::vector<std::int64_t>& block_first, int rank) {
  rank_blocks_.clear();
  rank_nodes_.clear();
  own_lo_ = 0;
  own_hi_ = std::numeric_limits<std::int32_t>::max();
  const int parts = static_cast<int>(block_first.size()) - 1;
  if (parts <= 1) return;
  if (rank < 0 || rank >= parts || block_first.back() != static_cast<std::int64_t>(m_.n_blocks()))
    throw std::logic_error("Simulation::distribute: ranges not of this model and rank");
  rank_blocks_ = block_first;
  for (auto b : block_first) rank_nodes_.push_back(m_.block_first_node[b]);
  own_lo_ = static_cast<std::int32_t>(block_first[rank]);
  own_hi_ = static_cast<std::int32_t>(block_first[rank + 1]);
  rank_ = rank;
  spring_first_.assign(parts + 1, 0);
  rank_slices_.assign(parts + 1, 0);
  // every interface's state, and a released-points count per rank
  spring_buf_.assign(m_.n_ifaces() * spring_state_doubles(m_) + parts, 0.0);
}

std::pair<std::int64_t, std::int64_t> Simulation::spring_share() {
  if (rank_blocks_.empty()) return {0, std::numeric_limits<std::int64_t>::max()};
  // Equal shares of the list (the interfaces cost alike): tied mode the active interfaces, which
  // every rank holds in the same order (order_active_ifaces), springs mode all interfaces.
  const std::int64_t n = m_.tied ? static_cast<std::int64_t>(m_.active_ifaces.size())
                                 : static_cast<std::int64_t>(m_.n_ifaces());
  const int parts = static_cast<int>(spring_first_.size()) - 1;
  for (int r = 0; r <= parts; ++r) spring_first_[r] = n * r / parts;
  return {spring_first_[rank_], spring_first_[rank_ + 1]};
}

void Simulation::share_springs(std::int64_t released_before) {
  const int parts = static_cast<int>(spring_first_.size()) - 1;
  const int d = spring_state_doubles(m_);
  const std::int32_t* list = m_.tied ? m_.active_ifaces.data() : nullptr;
  // Rank r's slice: its interfaces' states, then its count of released points.
  std::vector<std::int64_t>& at = rank_slices_;
  for (int r = 0; r <= parts; ++r) at[r] = spring_first_[r] * d + r;
  const std::int64_t lo = spring_first_[rank_], hi = spring_first_[rank_ + 1];
  pack_spring_state(m_, list, lo, hi, spring_buf_.data() + at[rank_]);
  spring_buf_[at[rank_ + 1] - 1] = static_cast<double>(m_.released_points - released_before);
  share_slices(spring_buf_.data(), at, 1);
  std::int64_t released = 0;
  for (int r = 0; r < parts; ++r) {
    if (r != rank_)
      unpack_spring_state(m_, list, spring_first_[r], spring_first_[r + 1], spring_buf_.data() + at[r]);
    released += static_cast<std::int64_t>(spring_buf_[at[r + 1] - 1]);
  }
  m_.released_points = released_before + released;
}

std::int64_t Simulation::share_blocks(std::int64_t inverted) {
  share_slices(&m_.f.data()->x, rank_nodes_, 3);
  share_slices(m_.stress.data()->data(), rank_blocks_, 6);
  share_slices(m_.strain_energy.data(), rank_blocks_, 1);
  share_slices(m_.vol_ratio.data(), rank_blocks_, 1);
  return max_over_ranks(inverted);
}

std::size_t Simulation::solver_bytes() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  std::size_t b = bytes(block_dissipated_) + bytes(ke_) + bytes(cke_) + bytes(vtx_dissipated_) +
                  bytes(vtx_ke_) + bytes(vtx_cke_) + bytes(vtx_reaction_) + bytes(vtx_con_) +
                  bytes(con_vertices_) + bytes(tie_flag_) + bytes(applied_.node) +
                  bytes(applied_.force) + bytes(applied_.pair_b) + bytes(applied_.pair_a) +
                  bytes(applied_.pair_force);
  b += bytes(bc_.constraints) + bytes(bc_.loads) + bytes(bc_.tables) + bytes(bc_.work_nodes) +
       bytes(bc_.v_old) + bytes(bc_.node_load_offset) +
       bytes(bc_.node_load_entry) + bytes(bc_.load_force);
  return b;
}

EnergyBalance Simulation::energy() const {
  // Each term once, summed exactly (core/exact_sum.hpp): the same bits for any order and, in the
  // halo stage of a distributed run, for any split of the model among the ranks: a part lists
  // the terms of the entities it owns (own_masks) and the sums are reduced over the ranks.
  enum : std::size_t { kKinetic, kDamping, kLastDamping, kBlockStrain, kSpringStrain, kFracture, kGravity, kProducts, kSums };
  const OwnMasks own = own_masks();
  constexpr auto mine = &OwnMasks::mine;
  const bool after_step = steps_ > 0;
  const std::vector<double> sum = sum_exactly(kSums, [&](auto&& put) {
    for (std::size_t v = 0; v < vtx_ke_.size(); ++v) {
      if (!mine(own.vertex, v)) continue;
      put(kKinetic, vtx_ke_[v]);
      if (!vtx_dissipated_.empty()) put(kDamping, vtx_dissipated_[v]);
      if (after_step && !vtx_cke_.empty()) put(kLastDamping, vtx_cke_[v]);
    }
    for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
      if (!mine(own.block, b)) continue;
      if (!ke_.empty()) put(kKinetic, ke_[b]);
      if (!block_dissipated_.empty()) put(kDamping, block_dissipated_[b]);
      if (after_step && !cke_.empty()) put(kLastDamping, cke_[b]);
      put(kBlockStrain, m_.strain_energy[b]);
      // The products' kinetic energy, in the same measure as `kinetic`: each block's (untied) or
      // cluster's (tied) leapfrog kinetic energy, times the products' share of its mass. A tied
      // cluster moves as one: its share is the products' mass in it over its mass.
      const double share = m_.block_materials[m_.block_material[b]].products_fraction();
      if (!(share > 0)) continue;
      if (!m_.tied) {
        put(kProducts, share * ke_[b]);
        continue;
      }
      for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n) {
        const auto v = m_.node_vertex[n];
        double mv = 0;
        for (auto q = m_.vtx_offset[v]; q < m_.vtx_offset[v + 1]; ++q) mv += m_.mass[m_.vtx_nodes[q]];
        put(kProducts, share * m_.mass[n] / mv * vtx_ke_[v]);
      }
    }
    // (per interface, its points' terms added first in point order: a term of the exact sums need
    // only be the same wherever it is formed)
    const auto np = static_cast<std::size_t>(m_.springs_per_iface);
    for (std::size_t i = 0; i < m_.n_ifaces(); ++i) {
      if (!mine(own.iface, i)) continue;
      double dissipated = 0, strain = 0;
      for (std::size_t s = i * np; s < (i + 1) * np; ++s) {
        dissipated += m_.sp_dissipated[s];
        if (m_.sp_state[s] != kReleased)
          strain += 0.5 * m_.sp_fn[s] * m_.sp_fn[s] / m_.sp_kn[s] + 0.5 * dot(m_.sp_fs[s], m_.sp_fs[s]) / m_.sp_ks[s];
      }
      put(kFracture, dissipated);
      put(kSpringStrain, strain);
    }
    if (bc_.gravity.x != 0 || bc_.gravity.y != 0 || bc_.gravity.z != 0)
      for (std::size_t b = 0; b < m_.n_blocks(); ++b) {  // (a block's nodes' terms added first)
        if (!mine(own.block, b)) continue;
        double w = 0;
        for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n)
          w += m_.mass[n] * dot(bc_.gravity, m_.x[n] - m_.X(n));
        put(kGravity, w);
      }
  }, halo_ ? rank_reducer() : nullptr);
  EnergyBalance e;
  e.kinetic = sum[kKinetic];
  e.damping = sum[kDamping];
  e.block_strain = sum[kBlockStrain];
  e.spring_strain = sum[kSpringStrain];
  e.fracture = sum[kFracture];
  e.gravity_work = sum[kGravity];
  // The accumulated works include all of the last step, F(n) . v_mid dt with
  // v_mid dt = (x(n+1) - x(n-1)) / 2; the state is at t_n (x(n), and the kinetic energy
  // 1/2 m v(n-1/2).v(n+1/2)), so the part after t_n, F(n) . v(n+1/2) dt / 2 (last_*_, and the
  // damping's c ke terms), is taken back out. With the leapfrog kinetic energy this makes the
  // balance exact for a linear system under any loads (docs/theory.md "Energy balance"): by
  // summation by parts the central-difference scheme conserves
  // E*(n) - sum_k<n F(k) . v_mid(k) dt - F(n) . v(n-1/2) dt/2.
  e.damping += w_absorbed_ - last_absorbed_ - sum[kLastDamping];
  e.damping -= w_sdamp_ - last_sdamp_;  // the damping forces' work is negative
  e.external_work = w_boundary_ - last_boundary_;
  e.explosive_work = w_explosive_ - last_explosive_;
  e.initial = e_initial_;
  e.insertion = w_insert_;
  e.contact_strain = contact_energy(contact_);
  e.contact_friction = contact_dissipated(contact_);
  e.products_kinetic = sum[kProducts];
  const double stored = e.mechanical() + e.damping + e.fracture + e.contact_friction;
  const double input =
      e.initial + e.external_work + e.gravity_work + e.explosive_work + e.insertion;
  e.balance = stored - input;
  const double scale = std::max({std::abs(input), e.mechanical(), 1e-300});
  e.error = std::abs(e.balance) / scale;
  return e;
}

void Simulation::io_state(StateArchive& ar) {
  cdem::io_state(ar, m_);
  cdem::io_state(ar, contact_);
  if (ar.loading() && contact_.enabled) {
    index_pairs(m_, contact_);
    reset_contact_sleep(m_, contact_);
    // (the release trigger's counts: the state's, as when the checkpoint was written, after its
    // step's look; contact_release.cpp)
    sync_release_counts(m_, contact_);
  }
  ar.io("sim.t", t_);
  ar.io("sim.dt", dt_);
  ar.io("sim.steps", steps_);
  ar.io("sim.inverted", inverted_);
  ar.io("sim.first_inverted", first_inverted_);
  ar.io("sim.block_dissipated", block_dissipated_);
  ar.io("sim.ke", ke_);
  ar.io("sim.cke", cke_);
  ar.io("sim.vtx_dissipated", vtx_dissipated_);
  ar.io("sim.vtx_ke", vtx_ke_);
  ar.io("sim.vtx_cke", vtx_cke_);
  ar.io("sim.vtx_reaction", vtx_reaction_);
  ar.io("sim.vtx_con", vtx_con_);
  ar.io("sim.con_vertices", con_vertices_);
  ar.io("sim.tie_flag", tie_flag_);
  ar.io("sim.w_insert", w_insert_);
  ar.io("sim.omega2_max", omega2_max_);
  ar.io("sim.opened", opened_);
  ar.io("sim.w_boundary", w_boundary_);
  ar.io("sim.w_absorbed", w_absorbed_);
  ar.io("sim.w_explosive", w_explosive_);
  ar.io("sim.e_initial", e_initial_);
  ar.io("sim.last_boundary", last_boundary_);
  ar.io("sim.last_absorbed", last_absorbed_);
  ar.io("sim.last_explosive", last_explosive_);
  if (beta_max_ > 0) {  // (only then: checkpoints of undamped runs keep their records)
    ar.io("sim.w_sdamp", w_sdamp_);
    ar.io("sim.last_sdamp", last_sdamp_);
  }
  ar.io("sim.bc_v_old", bc_.v_old);
  ar.io("sim.bc_load_force", bc_.load_force);
  // (the step's applied loads are not state: each step lists its own before it uses them)
}

}  // namespace cdem
