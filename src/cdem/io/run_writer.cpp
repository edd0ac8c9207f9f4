#include "cdem/io/run_writer.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "cdem/analysis/blast_quality.hpp"
#include "cdem/analysis/damage.hpp"
#include "cdem/analysis/monitors.hpp"

namespace cdem {
namespace fs = std::filesystem;

namespace {
std::FILE* open_csv(const std::string& path, const std::string& header) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error(fmt::format("cannot write '{}'", path));
  std::fputs(header.c_str(), f);
  return f;
}

// A history continued after a restart: cut back to `bytes` (its size at the checkpoint; rows
// written after it are written again) and opened for appending. 0 bytes: not created yet.
std::FILE* continue_csv(const std::string& path, std::int64_t bytes) {
  if (bytes <= 0) return nullptr;
  std::error_code ec;
  const auto have = fs::file_size(path, ec);
  if (ec || static_cast<std::int64_t>(have) < bytes)
    throw std::runtime_error(fmt::format("cannot restart: '{}' is missing or shorter ({} bytes) than "
                                         "at the checkpoint ({} bytes)",
                                         path, ec ? 0 : have, bytes));
  fs::resize_file(path, static_cast<std::uintmax_t>(bytes), ec);
  if (ec) throw std::runtime_error(fmt::format("cannot restart: cannot cut '{}' back: {}", path, ec.message()));
  std::FILE* f = std::fopen(path.c_str(), "a");
  if (!f) throw std::runtime_error(fmt::format("cannot write '{}'", path));
  return f;
}

std::int64_t csv_bytes(std::FILE* f) {
  if (!f) return 0;
  std::fflush(f);
  return static_cast<std::int64_t>(std::ftell(f));
}
}  // namespace

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\', o += ch;
    else if (ch == '\n') o += "\\n";
    else if (static_cast<unsigned char>(ch) < 0x20) o += fmt::format("\\u{:04x}", static_cast<int>(ch));
    else o += ch;
  }
  return o + "\"";
}
std::string json_number(double x) { return std::isfinite(x) ? fmt::format("{:.10g}", x) : "null"; }

std::string csv_column_name(const std::string& name) {
  std::string o = name;
  for (char& ch : o)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.')) ch = '_';
  return o;
}

void write_json(const std::string& path, const std::vector<std::pair<std::string, std::string>>& kv) {
  std::ofstream o(path);
  if (!o) throw std::runtime_error(fmt::format("cannot write '{}'", path));
  o << "{\n";
  for (std::size_t i = 0; i < kv.size(); ++i)
    o << "  " << json_string(kv[i].first) << ": " << kv[i].second << (i + 1 < kv.size() ? ",\n" : "\n");
  o << "}\n";
}

RunWriter::RunWriter(const std::string& dir, const Case& c, const Model* m, const std::string& run_id,
                     const std::string& charges_header, StateArchive* resume)
    : dir_(dir), case_(c), run_id_(run_id) {
  fs::create_directories(fs::path(dir) / "fields");
  fs::create_directories(fs::path(dir) / "cracks");
  fs::create_directories(fs::path(dir) / "fragments");
  {
    std::ofstream o(fs::path(dir) / "case.resolved.toml");
    if (!o) throw std::runtime_error(fmt::format("cannot write into '{}'", dir));
    if (!run_id.empty()) o << "# cdemblast run_id " << run_id << "\n";
    o << resolved_case_toml(c);
  }
  std::string fracture_header = "time,degree_area,tensile_area,shear_area,degree_count,broken,total";
  if (m) {
    fracture_regions_ = fracture_degree_by_region(*m).regions;
    for (auto r : fracture_regions_) fracture_header += ",degree_area_" + csv_column_name(m->region_names[r]);
  }
  const std::string monitors_header =
      "time,monitor,sxx,syy,szz,sxy,syz,sxz,von_mises,pressure,ux,uy,uz,vx,vy,vz\n";
  const std::string energy_header =
      "time,kinetic,block_strain,spring_strain,external_work,gravity_work,"
      "explosive_work,damping,fracture,initial,insertion,contact_strain,contact_friction,"
      "products_kinetic,balance,error\n";
  const std::string p_monitors = (fs::path(dir) / "monitors.csv").string();
  const std::string p_energy = (fs::path(dir) / "energy.csv").string();
  const std::string p_fracture = (fs::path(dir) / "fracture.csv").string();
  const std::string p_reactions = (fs::path(dir) / "reactions.csv").string();
  const std::string p_charges = (fs::path(dir) / "charges.csv").string();
  std::vector<std::pair<double, std::string>> fields_steps, cracks_steps;
  if (resume) {
    std::int64_t b_mon = 0, b_en = 0, b_fr = 0, b_re = 0, b_ch = 0;
    resume->io("writer.monitors_bytes", b_mon);
    resume->io("writer.energy_bytes", b_en);
    resume->io("writer.fracture_bytes", b_fr);
    resume->io("writer.reactions_bytes", b_re);
    resume->io("writer.charges_bytes", b_ch);
    resume->io("writer.frame", frame_);
    std::vector<double> ft, ct;
    std::vector<std::string> fn, cn;
    resume->io("writer.fields_times", ft);
    resume->io("writer.fields_files", fn);
    resume->io("writer.cracks_times", ct);
    resume->io("writer.cracks_files", cn);
    if (fn.size() != ft.size() || cn.size() != ct.size())
      throw std::runtime_error("cannot restart: the checkpoint's PVD entries are inconsistent");
    for (std::size_t i = 0; i < ft.size(); ++i) fields_steps.emplace_back(ft[i], fn[i]);
    for (std::size_t i = 0; i < ct.size(); ++i) cracks_steps.emplace_back(ct[i], cn[i]);
    monitors_ = continue_csv(p_monitors, b_mon);
    energy_ = continue_csv(p_energy, b_en);
    fracture_ = continue_csv(p_fracture, b_fr);
    reactions_ = continue_csv(p_reactions, b_re);
    if (!charges_header.empty()) charges_ = continue_csv(p_charges, b_ch);
  }
  if (!monitors_) monitors_ = open_csv(p_monitors, monitors_header);
  if (!energy_) energy_ = open_csv(p_energy, energy_header);
  if (!fracture_) fracture_ = open_csv(p_fracture, fracture_header + "\n");
  if (!charges_ && !charges_header.empty()) charges_ = open_csv(p_charges, charges_header);
  fields_pvd_ = std::make_unique<PvdWriter>((fs::path(dir) / "fields.pvd").string(), fields_steps, run_id);
  cracks_pvd_ = std::make_unique<PvdWriter>((fs::path(dir) / "cracks.pvd").string(), cracks_steps, run_id);
}

void RunWriter::io_state(StateArchive& ar) {
  std::int64_t b_mon = csv_bytes(monitors_), b_en = csv_bytes(energy_), b_fr = csv_bytes(fracture_),
               b_re = csv_bytes(reactions_), b_ch = csv_bytes(charges_);
  ar.io("writer.monitors_bytes", b_mon);
  ar.io("writer.energy_bytes", b_en);
  ar.io("writer.fracture_bytes", b_fr);
  ar.io("writer.reactions_bytes", b_re);
  ar.io("writer.charges_bytes", b_ch);
  ar.io("writer.frame", frame_);
  std::vector<double> ft, ct;
  std::vector<std::string> fn, cn;
  for (const auto& [t, f] : fields_pvd_->steps()) ft.push_back(t), fn.push_back(f);
  for (const auto& [t, f] : cracks_pvd_->steps()) ct.push_back(t), cn.push_back(f);
  ar.io("writer.fields_times", ft);
  ar.io("writer.fields_files", fn);
  ar.io("writer.cracks_times", ct);
  ar.io("writer.cracks_files", cn);
}

void RunWriter::check_written() {
  const std::pair<std::FILE*, const char*> files[] = {{monitors_, "monitors.csv"}, {energy_, "energy.csv"},
                                                      {fracture_, "fracture.csv"}, {reactions_, "reactions.csv"},
                                                      {charges_, "charges.csv"}};
  for (const auto& [f, name] : files)
    if (f && (std::fflush(f) != 0 || std::ferror(f)))
      throw std::runtime_error(fmt::format("cannot write '{}': {}", (fs::path(dir_) / name).string(),
                                           std::strerror(errno ? errno : EIO)));
}

RunWriter::~RunWriter() {
  for (auto* f : {monitors_, energy_, fracture_, reactions_, charges_})
    if (f) std::fclose(f);
}

void RunWriter::flush() {
  for (auto* f : {monitors_, energy_, fracture_, reactions_, charges_})
    if (f) std::fflush(f);
}

void RunWriter::write_reactions(double t, const std::vector<std::string>& face_sets,
                                const std::vector<Vec3>& force) {
  if (face_sets.empty()) return;
  if (!reactions_) reactions_ = open_csv((fs::path(dir_) / "reactions.csv").string(), "time,face_set,fx,fy,fz\n");
  for (std::size_t k = 0; k < face_sets.size(); ++k)
    std::fprintf(reactions_, "%.9g,%s,%.9g,%.9g,%.9g\n", t, face_sets[k].c_str(), force[k].x, force[k].y,
                 force[k].z);
}

namespace {
// The blocks as VTK cells, each with its own nodes at `points` (cracks open as gaps).
VtuMesh block_cells(const Model& m, std::vector<Vec3> points) {
  VtuMesh vm;
  vm.points = std::move(points);
  const std::size_t nb = m.n_blocks();
  vm.types.reserve(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) vm.connectivity.push_back(n);
    vm.offsets.push_back(static_cast<std::int64_t>(vm.connectivity.size()));
    vm.types.push_back(m.block_type[b] == ElemType::Tri3   ? kVtkTriangle
                       : m.block_type[b] == ElemType::Quad4 ? kVtkQuad : kVtkTetra);
  }
  return vm;
}
}  // namespace

void RunWriter::write_partition(const Model& m, const std::vector<std::int32_t>& part) {
  VtuMesh vm = block_cells(m, m.X_nodes());
  vm.cell_data.push_back(VtuArray{"part", 1, {}, part, VtuType::kInt32});
  write_vtu((std::filesystem::path(dir_) / "partition.vtu").string(), vm);
}

void RunWriter::write_fields(const Model& m, double t, const std::vector<double>* max_up,
                             const std::vector<float>* gas_pressure) {
  const std::string name = fmt::format("{:04d}", frame_++);
  // ---- blocks, each with its own nodes (cracks open as gaps) ----
  VtuMesh vm = block_cells(m, m.x);
  vm.time = t;
  const std::size_t nb = m.n_blocks();
  VtuArray disp{"displacement", 3, {}, {}}, vel{"velocity", 3, {}, {}};
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    const Vec3 u = m.x[n] - m.X(n);
    disp.f64.insert(disp.f64.end(), {u.x, u.y, u.z});
    vel.f64.insert(vel.f64.end(), {m.v[n].x, m.v[n].y, m.v[n].z});
  }
  vm.point_data = {std::move(disp), std::move(vel)};
  if (max_up && max_up->size() == m.n_nodes())
    vm.point_data.push_back(VtuArray{"max_up_displacement", 1, *max_up, {}});
  std::vector<double> damage;
  std::vector<std::int32_t> mode;
  block_damage(m, damage, mode);
  VtuArray stress{"stress", 6, {}, {}}, pres{"pressure", 1, {}, {}}, vmis{"von_mises", 1, {}, {}},
      dmg{"damage", 1, damage, {}}, dmode{"damage_mode", 1, {}, mode, VtuType::kInt32},
      reg{"region", 1, {}, {}, VtuType::kInt32},
      jr{"volume_ratio", 1, m.vol_ratio, {}};
  for (std::size_t b = 0; b < nb; ++b) {
    const Sym6& s = m.stress[b];
    stress.f64.insert(stress.f64.end(), s.begin(), s.end());
    pres.f64.push_back(pressure(s));
    vmis.f64.push_back(von_mises(s));
    reg.i32.push_back(m.block_region[b]);
  }
  const FragmentResult frag = model_fragments(m);
  VtuArray fid{"fragment_id", 1, {}, frag.fragment_of_block, VtuType::kInt32};
  vm.cell_data = {std::move(stress), std::move(pres), std::move(vmis), std::move(dmg),
                  std::move(dmode), std::move(reg), std::move(jr), std::move(fid)};
  {
    // One row per fragment (ids by decreasing volume: 0 is the largest).
    const std::string path = (fs::path(dir_) / "fragments" / ("fragments_" + name + ".csv")).string();
    std::FILE* f = open_csv(path, "id,blocks,volume,l_max,l_bc,cx,cy,cz,vx,vy,vz\n");
    for (std::size_t k = 0; k < frag.fragments.size(); ++k) {
      const auto& fr = frag.fragments[k];
      if (fr.volume <= 0) continue;
      std::fprintf(f, "%zu,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", k, fr.blocks, fr.volume,
                   fr.l_max, fr.l_bc, fr.centroid.x, fr.centroid.y, fr.centroid.z, fr.velocity.x,
                   fr.velocity.y, fr.velocity.z);
    }
    std::fclose(f);
  }
  const std::string rel = "fields/fields_" + name + ".vtu";
  write_vtu((fs::path(dir_) / rel).string(), vm);
  fields_pvd_->add(t, rel);

  // ---- cracks: interfaces with at least one broken (rock) spring point ----
  VtuMesh cm;
  cm.time = t;
  VtuArray cmode{"mode", 1, {}, {}, VtuType::kInt32}, cfrac{"broken_fraction", 1, {}, {}}, ctime{"break_time", 1, {}, {}};
  VtuArray cgas{"gas_pressure", 1, {}, {}};
  const bool has_gas = gas_pressure && gas_pressure->size() == m.n_ifaces();
  const int np = m.springs_per_iface;
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    int broken = 0, shear = 0;
    double tb = 1e300;
    for (int q = 0; q < np; ++q) {
      const auto s = i * np + q;
      if (m.sp_state[s] == kIntact || !counts_as_rock(m, s)) continue;
      ++broken;
      shear += m.sp_mode[s] == kModeShear;
      tb = std::min(tb, static_cast<double>(m.sp_break_time[s]));
    }
    if (!broken) continue;
    for (int q = 0; q < np; ++q) {
      cm.points.push_back(m.x[m.sp_a[i * np + q]]);
      cm.connectivity.push_back(static_cast<std::int64_t>(cm.points.size() - 1));
    }
    cm.offsets.push_back(static_cast<std::int64_t>(cm.connectivity.size()));
    cm.types.push_back(np == 2 ? kVtkLine : kVtkTriangle);
    cmode.i32.push_back(2 * shear > broken ? 2 : 1);
    cfrac.f64.push_back(static_cast<double>(broken) / np);
    ctime.f64.push_back(tb);
    cgas.f64.push_back(has_gas ? static_cast<double>((*gas_pressure)[i]) : 0.0);
  }
  cm.cell_data = {std::move(cmode), std::move(cfrac), std::move(ctime), std::move(cgas)};
  const std::string crel = "cracks/cracks_" + name + ".vtu";
  write_vtu((fs::path(dir_) / crel).string(), cm);
  cracks_pvd_->add(t, crel);
}

void RunWriter::write_history(const Model& m, double t, const EnergyBalance& e, const FractureDegree& fd,
                              const std::vector<double>& region_degree,
                              const std::vector<std::int32_t>& monitor_blocks) {
  for (std::size_t k = 0; k < monitor_blocks.size(); ++k) {
    const MonitorSample s = sample_block(m, monitor_blocks[k]);
    std::fprintf(monitors_, "%.9g,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
                 t, case_.monitors[k].name.c_str(), s.stress[0], s.stress[1], s.stress[2],
                 s.stress[3], s.stress[4], s.stress[5], s.von_mises, s.pressure, s.displacement.x,
                 s.displacement.y, s.displacement.z, s.velocity.x, s.velocity.y, s.velocity.z);
  }
  std::fprintf(energy_, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g\n",
               t, e.kinetic, e.block_strain, e.spring_strain, e.external_work, e.gravity_work,
               e.explosive_work, e.damping, e.fracture, e.initial, e.insertion, e.contact_strain,
               e.contact_friction, e.products_kinetic, e.balance, e.error);
  std::fprintf(fracture_, "%.9g,%.9g,%.9g,%.9g,%.9g,%lld,%lld", t, fd.area, fd.tensile, fd.shear,
               fd.count, static_cast<long long>(fd.broken), static_cast<long long>(fd.total));
  if (!fracture_regions_.empty())
    for (double d : region_degree) std::fprintf(fracture_, ",%.9g", d);
  std::fputs("\n", fracture_);
}

}  // namespace cdem
