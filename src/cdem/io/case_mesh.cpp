#include "cdem/io/case_sections.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "cdem/core/error.hpp"
#include "cdem/mesh/mesh_estimate.hpp"

namespace cdem {

namespace {

namespace fs = std::filesystem;

std::string resolve_path(const std::string& dir, const std::string& p) {
  fs::path q(p);
  return q.is_absolute() ? q.string() : (fs::path(dir) / q).lexically_normal().string();
}

// A 2D geometry (rectangle) takes [x, y]; a z would be dropped by the mesher.
void no_z_in_2d(const TomlTable& t, const std::string& key, double z) {
  if (z != 0)
    throw InputError(fmt::format("{}: z = {:g} for a rectangle (a 2D mesh in the plane z = 0); "
                                 "it would be dropped: give [x, y]",
                                 t.where(key), z));
}

// [[mesh.generate.refine]]: a ball around `point`, or with `to` a segment (a hole's axis).
RefineSpec parse_refine(const TomlTable& r) {
  r.check_known({"point", "to", "size", "radius", "grading"});
  RefineSpec rs;
  rs.point = r.vec("point");
  if (r.has("to")) {
    rs.to = r.vec("to");
    if (!(norm(*rs.to - rs.point) > 0))
      throw InputError(fmt::format("{}: the segment has zero length ('to' = 'point')", r.where("to")));
  }
  rs.size = r.positive("size");
  rs.radius = r.positive("radius");
  rs.grading = r.positive("grading", 0.0);
  return rs;
}

GenerateSpec parse_generate(const TomlTable& g) {
  g.check_known({"shape", "origin", "size", "element_size", "quads", "hole", "refine", "ring_width",
                 "ring_element_size", "region", "circle_segments", "wall_sizing"});
  GenerateSpec s;
  s.shape = g.choice("shape", {"rectangle", "box", "cylinder"}, "");
  s.origin = g.vec("origin", {});
  s.size = g.vec("size");
  const int need = s.shape == "rectangle" ? 2 : 3;
  if (need == 2) {
    no_z_in_2d(g, "origin", s.origin.z);
    no_z_in_2d(g, "size", s.size.z);
  }
  if (s.shape == "cylinder") {
    if (!(s.size.x > 0 && s.size.z > 0))
      throw InputError(fmt::format("{}: a cylinder needs size = [radius, 0, height], both > 0",
                                   g.where("size")));
  } else {
    if (!(s.size.x > 0 && s.size.y > 0 && (need == 2 || s.size.z > 0)))
      throw InputError(fmt::format("{}: expected {} positive lengths", g.where("size"), need));
  }
  s.element_size = g.positive("element_size");
  s.quads = g.boolean("quads", false);
  {
    const auto n = g.integer("circle_segments", 16);
    if (n < 0 || n > 1000)
      throw InputError(fmt::format("{}: expected an integer from 0 to 1000 (elements per full turn "
                                   "of a curved wall; 0: no curvature sizing), got {}",
                                   g.where("circle_segments"), n));
    s.circle_segments = static_cast<int>(n);
  }
  s.region = g.string("region", "rock");
  s.wall_sizing = g.choice("wall_sizing", {"finest", "refine"}, "finest");
  s.ring_width = g.non_negative("ring_width", 0.0);
  s.ring_element_size = g.positive("ring_element_size", s.element_size);
  for (const auto& h : g.array_of_tables("hole")) {
    h.check_known({"center", "radius", "axis", "depth", "region"});
    HoleSpec hs;
    hs.center = h.vec("center");
    hs.radius = h.positive("radius");
    hs.axis = h.vec("axis", need == 2 ? Vec3{0, -1, 0} : Vec3{0, 0, -1});
    if (need == 2) {
      no_z_in_2d(h, "center", hs.center.z);
      no_z_in_2d(h, "axis", hs.axis.z);
    }
    if (norm(hs.axis) == 0) throw InputError(fmt::format("{}: the axis is a zero vector", h.where("axis")));
    hs.axis = normalized(hs.axis);
    hs.depth = h.non_negative("depth", 0.0);
    hs.region = h.string("region", "");
    s.holes.push_back(hs);
  }
  for (const auto& r : g.array_of_tables("refine")) {
    RefineSpec rs = parse_refine(r);
    if (need == 2) {
      no_z_in_2d(r, "point", rs.point.z);
      if (rs.to) no_z_in_2d(r, "to", rs.to->z);
    }
    s.refine.push_back(rs);
  }
  return s;
}

}  // namespace

void parse_mesh(const TomlTable& top, Case& c) {
  const auto mesh = top.sub("mesh");
  if (!mesh)
    throw InputError(
        fmt::format("{}: missing table [mesh] (give 'file' or [mesh.generate])", c.path));
  mesh->check_known({"file", "generate"});
  if (mesh->has("file") == mesh->has("generate"))
    throw InputError(fmt::format("{}: [mesh] needs exactly one of 'file' (a Gmsh .msh) or "
                                 "[mesh.generate]",
                                 c.path));
  if (mesh->has("file")) {
    c.mesh_file = resolve_path(c.dir, mesh->string("file"));
  } else {
    c.generate = parse_generate(*mesh->sub("generate"));
    // Sized now, naming the key, before anything is meshed (generate_mesh checks again).
    const MeshEstimate est = estimate_generated_mesh(*c.generate);
    const std::string why = model_size_problem(
        est.elements, c.generate->shape == "rectangle" ? 2 : 3, "mostly from " + est.largest);
    if (!why.empty())
      throw InputError(
          fmt::format("{}: key 'mesh.generate.{}': {}", c.path, est.largest_key, why));
  }
}

}  // namespace cdem
