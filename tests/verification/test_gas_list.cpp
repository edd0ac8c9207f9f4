// The gas pass over a given crack list (explosive/gas.hpp, CrackInputs; the halo stage's list,
// solver/halo_charges.hpp) does what the pass over the whole list does. A distributed run sends
// only the interfaces the pass can act on (gas_candidate): if the rule missed one, a crack would
// take gas later, or a block be reached later, than in one process, and the runs would part.
//
// Here in one process, for every step of a cracking bar blast: a copy of the bars' state is
// stepped on the cut list, formed from the same model by the same rule, beside the run's own step
// on the whole list. The copy's state must be the run's, bit for bit: every interface's fill and
// gas body, every block's gas body, each deck's gas (pressure, volume, crack volume and mass,
// vented mass, work, plug), every bound block's pressure. Models: the 2D bar blast (SPEC 5.1's
// case, contact off, to 0.5 ms: its gas fills about a hundred cracks) and the 3D bar box of the
// halo tests, both interface modes. The cut list must also be shorter than the whole list (or
// the test checks nothing the whole list would not).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/io/case.hpp"
#include "cdem/solver/run.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

template <class T>
bool same_vec(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_body(const GasBody& a, const GasBody& b) {
  auto eq = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  return eq(a.burnt, b.burnt) && eq(a.vented, b.vented) && eq(a.v_cavity, b.v_cavity) &&
         eq(a.v_cracks, b.v_cracks) && eq(a.m_cracks, b.m_cracks) && eq(a.pressure, b.pressure) &&
         eq(a.work, b.work) && eq(a.plug_x, b.plug_x) && eq(a.plug_v, b.plug_v) &&
         a.plug_out == b.plug_out && eq(a.vent_area, b.vent_area);
}

void check_cut_list(const std::string& path, const std::vector<std::string>& sets, double end) {
  test_models::ScopedThreads th(1);
  const Case c = load_case(std::string(CDEM_SOURCE_DIR) + path, sets);
  PreparedCase pc = prepare_case(c, load_mesh(c));
  ASSERT_FALSE(pc.bars.empty());
  std::int64_t steps = 0, whole_entries = 0, cut_entries = 0, crack_steps = 0;
  std::string failed;
  pc.sim.add_load([&](Model& m, AppliedLoads& out, double t) {
    // the cut list, as a part owning every interface forms it (HaloCharges::load_bars)
    BarCharges cut = pc.bars;
    CrackInputs given;
    const std::size_t nlist = m.tied ? m.active_ifaces.size() : m.n_ifaces();
    for (std::size_t k = 0; k < nlist; ++k) {
      const std::size_t i = m.tied ? static_cast<std::size_t>(m.active_ifaces[k]) : k;
      const bool open = crack_open(m, i);
      const double w = open ? crack_aperture(m, i) : 0.0;
      if (!gas_candidate(m, cut.gas, i, open, w)) continue;
      given.iface.push_back(static_cast<std::int32_t>(i));
      given.open.push_back(open ? 1 : 0);
      given.aperture.push_back(w);
    }
    bar_state(m, cut, m.vol_ratio, t, &given);
    bar_loads(m, pc.bars, out, t);
    ++steps;
    whole_entries += static_cast<std::int64_t>(nlist);
    cut_entries += static_cast<std::int64_t>(given.iface.size());
    const GasField &a = pc.bars.gas, &b = cut.gas;
    bool ok = same_vec(a.iface_fill, b.iface_fill) && same_vec(a.iface_body, b.iface_body) &&
              same_vec(a.block_body, b.block_body) && same_vec(pc.bars.elem_sigma, cut.elem_sigma) &&
              same_vec(pc.bars.seg_p, cut.seg_p) && b.chain_overflow < 0;
    for (std::size_t k = 0; k < a.bodies.size(); ++k) {
      ok = ok && same_body(a.bodies[k], b.bodies[k]);
      if (a.bodies[k].v_cracks > 0 && k == 0) ++crack_steps;
    }
    if (!ok && failed.empty()) failed = "step " + std::to_string(steps) + ", t = " + std::to_string(t);
  });
  while (pc.sim.time() < end && failed.empty()) pc.sim.step();
  EXPECT_TRUE(failed.empty()) << path << " [" << name_of(c.interface_mode) << "]: the cut list's gas state differs at " << failed;
  std::int64_t filled = 0;
  for (float f : pc.bars.gas.iface_fill) filled += f > 0;
  std::printf("[gas list] %s [%s]: %lld steps (%lld with gas in cracks), %lld cracks filled; the cut list %.3g "
              "entries per step against the whole list's %.3g\n",
              path.c_str(), name_of(c.interface_mode), static_cast<long long>(steps),
              static_cast<long long>(crack_steps), static_cast<long long>(filled),
              static_cast<double>(cut_entries) / static_cast<double>(steps),
              static_cast<double>(whole_entries) / static_cast<double>(steps));
  EXPECT_GT(crack_steps, 0) << path;
  EXPECT_GT(filled, 10) << path;
  EXPECT_LT(cut_entries, whole_entries) << path;
}

TEST(GasList, CutListIsTheWholeList2D) {
  for (const char* mode : {"tied", "springs"})
    check_cut_list("/examples/single_hole_2d/bar.toml",
                   {"contact.enabled=false", std::string("simulation.interfaces=\"") + mode + "\""}, 5e-4);
}

TEST(GasList, CutListIsTheWholeList3D) {
  for (const char* mode : {"tied", "springs"})
    check_cut_list("/tests/verification/cases/bar_box_3d.toml",
                   {std::string("simulation.interfaces=\"") + mode + "\""}, 2.5e-4);
}

}  // namespace
}  // namespace cdem
