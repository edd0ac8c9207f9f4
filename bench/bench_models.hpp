// The models of the kernel benchmarks (bench_kernels.cpp), built once per process and copied
// into each benchmark (a kernel that moves the state works on its own copy).
//
// All are structured (no Gmsh, the same on every machine; builders in solver/bench.hpp) with
// cells of h = 0.05 m and about kBlocks blocks:
//   tet:  17 x 17 x 17 cubes, each split into the 6 Kuhn tetrahedra: 29 478 tets
//   tri:  122 x 123 squares, each split into 2 triangles:             30 012 triangles
//   quad: 173 x 173 squares:                                          29 929 quadrilaterals
// Rock: granite of SPEC 5.3 (E 99.3 GPa, nu 0.28, rho 2681); interfaces with the SPEC 5.3
// strengths (f_t 8.11 MPa, c 20 MPa, phi 35 deg, G_t 70, G_s 700 Pa.m), the law chosen per
// benchmark. State: a deterministic "mid-blast" field (bench::apply_bench_state): a per-vertex
// pseudo-random displacement of 5e-4 h (block strains of order 5e-4, so the polar decomposition
// iterates as it does in a run) on a rigid rotation of 0.02 rad, velocities of 1 m/s, and a
// per-node jitter that opens or closes the spring points by a chosen fraction of the tensile
// opening d_t = f_t / k_n (k_n = alpha E / h per unit area).
#pragma once
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "cdem/mesh/topology.hpp"
#include "cdem/model/model.hpp"
#include "cdem/solver/bench.hpp"
#include "cdem/solver/time_step.hpp"

namespace cdem::bench_models {

constexpr double kH = 0.05;
constexpr std::int64_t kBlocks = 30000;
constexpr double kStrain = 5e-4, kRotation = 0.02, kSpeed = 1.0;

enum class Shape { Tet, Tri, Quad };

inline Mesh make_mesh(Shape s) {
  switch (s) {
    case Shape::Tet: {
      const auto c = bench::tet_cells_for(kBlocks);
      return bench::structured_tet_box(c[0], c[1], c[2], kH);
    }
    case Shape::Tri: {
      const auto c = bench::tri_cells_for(kBlocks);
      return bench::structured_tri_grid(c[0], c[1], kH);
    }
    case Shape::Quad: {
      const auto c = bench::quad_cells_for(kBlocks);
      return bench::structured_quad_grid(c[0], c[1], kH);
    }
  }
  return {};
}

// The extent of the box (for bench::box_case).
inline Vec3 extent_of(const Mesh& mesh) {
  Vec3 hi{};
  for (const auto& p : mesh.vertices)
    for (int d = 0; d < 3; ++d) hi[d] = std::max(hi[d], p[d]);
  return hi;
}

// The model in its reference state (x = X, v = 0), Mohr-Coulomb interfaces; built once.
inline const Model& base_model(Shape s) {
  auto build = [](Shape sh) {
    const Mesh mesh = make_mesh(sh);
    return build_model(mesh, {bench::rock_material()},
                       {bench::interface_material(InterfaceLaw::MohrCoulomb)}, "bench model");
  };
  static const Model tet = build(Shape::Tet);
  static const Model tri = build(Shape::Tri);
  static const Model quad = build(Shape::Quad);
  return s == Shape::Tet ? tet : (s == Shape::Tri ? tri : quad);
}

// Tensile opening of an intact spring point, d_t = f_t / k_n (m).
inline double tensile_opening() {
  const auto mat = bench::rock_material();
  const auto im = bench::interface_material(InterfaceLaw::MohrCoulomb);
  return im.tensile_strength / (im.stiffness_factor * mat.youngs / kH);
}

// A copy of the base model with interfaces of `law`, in the mid-blast state (block strains of
// order `strain`) with spring points opened or closed by up to `jitter_dt` x d_t (per node, in
// each direction) and relative velocities of up to `speed_jitter` m/s.
inline Model state_model(Shape s, InterfaceLaw law, double jitter_dt, double speed_jitter,
                         double strain = kStrain) {
  Model m = base_model(s);
  const auto im = bench::interface_material(law);
  m.iface_materials = {im};
  m.spring_laws = {make_spring_law(im)};
  bench::apply_bench_state(m, kH, strain, kRotation, jitter_dt * tensile_opening(), kSpeed,
                           speed_jitter);
  return m;
}

// The stable time step of the model (safety 0.5).
inline double stable_dt(const Model& m) { return stable_time_step(m, 0.5).dt; }

// Spring state saved and restored around each benchmark iteration, so that every iteration
// starts from the same state (breaking and softening are irreversible).
struct SpringState {
  std::vector<double> fn, w, slip, dil, dissipated;
  std::vector<Vec3> fs, normal;
  std::vector<std::uint8_t> state, mode;
  std::vector<float> break_time;
  explicit SpringState(const Model& m)
      : fn(m.sp_fn),
        w(m.sp_w),
        slip(m.sp_slip),
        dil(m.sp_dil),
        dissipated(m.sp_dissipated),
        fs(m.sp_fs),
        normal(m.iface_normal),
        state(m.sp_state),
        mode(m.sp_mode),
        break_time(m.sp_break_time) {}
  void restore(Model& m) const {
    std::copy(fn.begin(), fn.end(), m.sp_fn.begin());
    std::copy(w.begin(), w.end(), m.sp_w.begin());
    std::copy(slip.begin(), slip.end(), m.sp_slip.begin());
    std::copy(dil.begin(), dil.end(), m.sp_dil.begin());
    std::copy(dissipated.begin(), dissipated.end(), m.sp_dissipated.begin());
    std::copy(fs.begin(), fs.end(), m.sp_fs.begin());
    std::copy(normal.begin(), normal.end(), m.iface_normal.begin());
    std::copy(state.begin(), state.end(), m.sp_state.begin());
    std::copy(mode.begin(), mode.end(), m.sp_mode.begin());
    std::copy(break_time.begin(), break_time.end(), m.sp_break_time.begin());
  }
};

}  // namespace cdem::bench_models
