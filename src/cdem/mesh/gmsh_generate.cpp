// Mesh generation with Gmsh's OpenCASCADE kernel: a rectangle (2D, z = 0), a box or a
// cylinder (axis z), with empty or filled holes, local refinements and an outer ring.
// The model is built with boolean operations (cut for empty holes, fragment for filled holes
// and the ring, so the mesh is conformal across their walls), meshed with a size field,
// labelled with physical groups, and turned into a Mesh by the same extraction (and checks)
// as read_gmsh.
#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/mesh_estimate.hpp"

namespace cdem {
namespace {

[[noreturn]] void spec_error(const std::string& what) {
  throw MeshError(fmt::format("mesh generation: {}", what));
}

// A predicate on points, used to find the boundary entities that make up a face set: an
// entity belongs to the face set when all its mesh nodes satisfy it.
struct Side {
  std::string name;
  std::function<bool(const Vec3&)> on;
};

struct Body {
  int dim = 2;
  double extent = 0;   // largest side (m)
  double measure = 0;  // area (m^2) or volume (m^3)
  Vec3 lo, hi;         // bounding box
};

Body check_spec(const GenerateSpec& s) {
  Body b;
  if (!(s.element_size > 0))
    spec_error(fmt::format("element_size must be > 0 (got {})", s.element_size));
  const Vec3 o = s.origin, z = s.size;
  if (s.shape == "rectangle") {
    if (!(z.x > 0 && z.y > 0))
      spec_error(fmt::format("rectangle size must be > 0 in x and y (got {}, {})", z.x, z.y));
    b.dim = 2;
    b.lo = {o.x, o.y, 0};
    b.hi = {o.x + z.x, o.y + z.y, 0};
    b.measure = z.x * z.y;
  } else if (s.shape == "box") {
    if (!(z.x > 0 && z.y > 0 && z.z > 0))
      spec_error(fmt::format("box size must be > 0 in x, y and z (got {}, {}, {})", z.x, z.y, z.z));
    b.dim = 3;
    b.lo = o;
    b.hi = o + z;
    b.measure = z.x * z.y * z.z;
  } else if (s.shape == "cylinder") {
    if (!(z.x > 0 && z.z > 0))
      spec_error(fmt::format(
          "cylinder radius (size.x) and height (size.z) must be > 0 (got {}, {})", z.x, z.z));
    b.dim = 3;
    b.lo = {o.x - z.x, o.y - z.x, o.z};
    b.hi = {o.x + z.x, o.y + z.x, o.z + z.z};
    b.measure = std::numbers::pi * z.x * z.x * z.z;
  } else {
    spec_error(fmt::format("unknown shape '{}' (expected rectangle, box or cylinder)", s.shape));
  }
  b.extent = std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z});
  if (s.region.empty()) spec_error("the main region needs a name");

  for (std::size_t i = 0; i < s.holes.size(); ++i) {
    const HoleSpec& h = s.holes[i];
    if (!(h.radius > 0))
      spec_error(fmt::format("hole {}: radius must be > 0 (got {})", i, h.radius));
    if (!(h.depth >= 0))
      spec_error(fmt::format("hole {}: depth must be >= 0 (got {})", i, h.depth));
    if (!(norm(h.axis) > 0)) spec_error(fmt::format("hole {}: axis must not be zero", i));
    if (b.dim == 2 && h.depth > 0 && !(std::hypot(h.axis.x, h.axis.y) > 1e-9 * norm(h.axis)))
      spec_error(fmt::format("hole {}: a 2D slot (depth > 0) needs an axis in the xy plane", i));
    if (h.region == "ring" && s.ring_width > 0)
      spec_error(fmt::format("hole {}: region name 'ring' is taken by the outer ring", i));
  }
  if (s.circle_segments < 0 || s.circle_segments > 1000)
    spec_error(fmt::format("circle_segments must be in 0..1000 (got {})", s.circle_segments));
  for (std::size_t i = 0; i < s.refine.size(); ++i) {
    const RefineSpec& r = s.refine[i];
    if (!(r.size > 0 && r.radius > 0))
      spec_error(fmt::format("refinement {}: size and radius must be > 0 (got {}, {})", i, r.size,
                             r.radius));
    if (!(r.grading >= 0))
      spec_error(fmt::format("refinement {}: grading must be >= 0 (got {})", i, r.grading));
    if (r.to && !(norm(*r.to - r.point) > 0))
      spec_error(fmt::format("refinement {}: the segment's ends 'point' and 'to' coincide", i));
  }
  if (s.wall_sizing != "finest" && s.wall_sizing != "refine")
    spec_error(fmt::format("wall_sizing must be \"finest\" or \"refine\" (got \"{}\")", s.wall_sizing));
  if (s.ring_width != 0) {
    if (s.shape != "cylinder") spec_error("ring_width is for the cylinder only");
    if (!(s.ring_width > 0 && s.ring_width < s.size.x))
      spec_error(fmt::format("ring_width must be > 0 and below the radius {} (got {})", s.size.x,
                             s.ring_width));
    if (!(s.ring_element_size >= 0)) spec_error("ring_element_size must be >= 0 (0: element_size)");
  }
  // wall_sizing "refine": inside a refinement zone the zone's size wins on a hole's wall, coarser
  // or finer. A wall cut into fewer than kMinWallSegments elements around is no hole any more,
  // and Gmsh's meshing of such a wall (a 40 mm hole in a 50 mm zone: 2.5 segments) ran for over
  // ten minutes with 8 GB before it was stopped: refused before Gmsh starts.
  if (s.wall_sizing == "refine" && s.circle_segments > 0) {
    constexpr int kMinWallSegments = 4;
    for (std::size_t i = 0; i < s.holes.size(); ++i) {
      const HoleSpec& h = s.holes[i];
      if (b.dim == 2 && h.depth > 0) continue;  // a 2D slot's walls are flat
      const double most = 2 * std::numbers::pi * h.radius / kMinWallSegments;
      for (std::size_t j = 0; j < s.refine.size(); ++j) {
        const RefineSpec& r = s.refine[j];
        if (!(r.size > most)) continue;
        // does the zone (its band included) reach the wall? The distance between the hole's
        // axis segment (a through hole: across the body) and the zone's point or segment,
        // sampled finely enough for this coarse test.
        Vec3 a = h.axis;
        if (b.dim == 2) a.z = 0;
        a = normalized(a);
        const double len = h.depth > 0 ? h.depth : 2 * b.extent;
        const Vec3 h0 = h.depth > 0 ? h.center : h.center - 0.5 * len * a;
        const Vec3 r1 = r.to ? *r.to : r.point;
        double d = std::numeric_limits<double>::infinity();
        constexpr int kSamples = 256;
        for (int u = 0; u <= kSamples; ++u) {
          Vec3 p = h0 + (len * u / kSamples) * a;
          if (b.dim == 2) p.z = r.point.z;
          const Vec3 sd = r1 - r.point;
          const double l2 = dot(sd, sd);
          const double t = l2 > 0 ? std::clamp(dot(p - r.point, sd) / l2, 0.0, 1.0) : 0.0;
          const Vec3 q = p - (r.point + t * sd);
          d = std::min(d, std::sqrt(dot(q, q)));
        }
        if (d <= refine_outer(r, s.element_size) + h.radius + len / kSamples)
          spec_error(fmt::format(
              "refinement {}: size {} m is on the wall of hole {} (radius {} m) with wall_sizing = "
              "\"refine\", which gives {:.1f} elements around it; at most {:.3g} m ({} around), or "
              "wall_sizing = \"finest\"",
              j, r.size, i, h.radius, 2 * std::numbers::pi * h.radius / r.size, most,
              kMinWallSegments));
      }
    }
  }
  // Before Gmsh meshes for minutes: the element count (refinements and curved walls included)
  // against the cap and this machine's memory (mesh_estimate.hpp).
  const MeshEstimate est = estimate_generated_mesh(s);
  check_model_size(est.elements, b.dim, "mesh generation", "mostly from " + est.largest);
  return b;
}

// The hole's frame: unit axis a, and in 2D the unit normal n = z x a (slot width direction).
struct HoleFrame {
  Vec3 c, a, n;
  double r = 0, depth = 0;
  bool through = false;
};

HoleFrame frame_of(const HoleSpec& h, int dim) {
  HoleFrame f;
  f.c = h.center;
  f.r = h.radius;
  f.depth = h.depth;
  f.through = h.depth == 0;
  if (dim == 2) {
    f.c.z = 0;
    f.a = normalized(Vec3{h.axis.x, h.axis.y, 0});
    f.n = Vec3{-f.a.y, f.a.x, 0};
  } else {
    f.a = normalized(h.axis);
  }
  return f;
}

// Is p on the boundary of the hole (tolerance tol)? 2D circle, 2D slot (rectangle), 3D
// through cylinder (its side), 3D drilled cylinder (side, bottom and collar discs).
bool on_hole_boundary(const HoleFrame& f, int dim, const Vec3& p, double tol) {
  const Vec3 d = p - f.c;
  if (dim == 2 && f.through) return std::abs(std::hypot(d.x, d.y) - f.r) < tol;
  const double s = dot(d, f.a);  // along the axis from the collar
  if (dim == 2) {
    const double t = dot(d, f.n);  // across the slot
    if (s < -tol || s > f.depth + tol || std::abs(t) > f.r + tol) return false;
    return std::abs(s) < tol || std::abs(s - f.depth) < tol || std::abs(std::abs(t) - f.r) < tol;
  }
  const double rho = norm(d - s * f.a);  // distance to the axis
  if (f.through) return std::abs(rho - f.r) < tol;
  if (s < -tol || s > f.depth + tol || rho > f.r + tol) return false;
  return std::abs(rho - f.r) < tol || std::abs(s) < tol || std::abs(s - f.depth) < tol;
}

std::vector<Side> outer_sides(const GenerateSpec& s, const Body& b, double tol) {
  std::vector<Side> sides;
  const Vec3 lo = b.lo, hi = b.hi;
  if (s.shape == "cylinder") {
    const Vec3 o = s.origin;
    const double radius = s.size.x;
    sides.push_back({"side", [=](const Vec3& p) {
                       return std::abs(std::hypot(p.x - o.x, p.y - o.y) - radius) < tol;
                     }});
    sides.push_back({"bottom", [=](const Vec3& p) { return std::abs(p.z - lo.z) < tol; }});
    sides.push_back({"top", [=](const Vec3& p) { return std::abs(p.z - hi.z) < tol; }});
    return sides;
  }
  sides.push_back({"left", [=](const Vec3& p) { return std::abs(p.x - lo.x) < tol; }});
  sides.push_back({"right", [=](const Vec3& p) { return std::abs(p.x - hi.x) < tol; }});
  if (b.dim == 2) {
    sides.push_back({"bottom", [=](const Vec3& p) { return std::abs(p.y - lo.y) < tol; }});
    sides.push_back({"top", [=](const Vec3& p) { return std::abs(p.y - hi.y) < tol; }});
  } else {
    sides.push_back({"front", [=](const Vec3& p) { return std::abs(p.y - lo.y) < tol; }});
    sides.push_back({"back", [=](const Vec3& p) { return std::abs(p.y - hi.y) < tol; }});
    sides.push_back({"bottom", [=](const Vec3& p) { return std::abs(p.z - lo.z) < tol; }});
    sides.push_back({"top", [=](const Vec3& p) { return std::abs(p.z - hi.z) < tol; }});
  }
  return sides;
}

std::string num(double v) { return fmt::format("{:.17g}", v); }

// The OCC entity of a hole (before any boolean operation).
std::pair<int, int> make_hole_tool(const HoleFrame& f, const Body& b) {
  namespace occ = gmsh::model::occ;
  if (b.dim == 2) {
    if (f.through) return {2, occ::addDisk(f.c.x, f.c.y, 0, f.r, f.r)};
    // A slot: the blasthole of a plane strain model is a plain rectangle, width 2r, from the
    // collar along the axis for the depth (no rounded bottom: in plane strain the hole is a
    // slot through the thickness, and a flat bottom keeps the charge region a clean block of
    // quadrilaterals). Corners computed directly so that axis-aligned slots are exact.
    const Vec3 c0 = f.c - f.r * f.n, c1 = f.c + f.depth * f.a - f.r * f.n,
               c2 = f.c + f.depth * f.a + f.r * f.n, c3 = f.c + f.r * f.n;
    std::vector<int> pts, lines;
    for (const Vec3& p : {c0, c1, c2, c3}) pts.push_back(occ::addPoint(p.x, p.y, 0));
    for (std::size_t i = 0; i < 4; ++i) lines.push_back(occ::addLine(pts[i], pts[(i + 1) % 4]));
    const int loop = occ::addCurveLoop(lines);
    return {2, occ::addPlaneSurface({loop})};
  }
  if (!f.through) {
    const Vec3 d = f.depth * f.a;
    return {3, occ::addCylinder(f.c.x, f.c.y, f.c.z, d.x, d.y, d.z, f.r)};
  }
  // Through the whole body: a cylinder longer than the body on both sides.
  const Vec3 mid = 0.5 * (b.lo + b.hi);
  const double length = 2.0 * (norm(b.hi - b.lo) + norm(f.c - mid)) + f.r;
  const Vec3 start = f.c - length * f.a, d = 2.0 * length * f.a;
  return {3, occ::addCylinder(start.x, start.y, start.z, d.x, d.y, d.z, f.r)};
}

// Intersection of `tool` with a copy of the body: the part of the tool inside the body.
gmsh::vectorpair clip_to_body(const gmsh::vectorpair& body, std::pair<int, int> tool) {
  namespace occ = gmsh::model::occ;
  gmsh::vectorpair copy, out;
  std::vector<gmsh::vectorpair> map;
  occ::copy(body, copy);
  occ::intersect({tool}, copy, out, map, -1, true, true);
  return out;
}

// ---- size fields (Gmsh MathEval expressions of x, y, z; Gmsh's MathEx knows Sqrt, Abs, Max) ----

// Distance from (x, y, z) to the refinement's point, or to its segment point..to: with
// t = (p - a).(b - a) / |b - a|^2 clamped to [0, 1] (1 - Max(0, 1 - Max(0, t))), the distance
// |p - a - t (b - a)|. 2D: in the xy plane.
std::string refine_distance(const RefineSpec& r, int dim) {
  const Vec3 a = r.point;
  const std::string dx = fmt::format("(x-({}))", num(a.x)), dy = fmt::format("(y-({}))", num(a.y)),
                    dz = fmt::format("(z-({}))", num(a.z));
  if (!r.to) {
    return dim == 2 ? fmt::format("Sqrt({0}^2+{1}^2)", dx, dy)
                    : fmt::format("Sqrt({0}^2+{1}^2+{2}^2)", dx, dy, dz);
  }
  Vec3 d = *r.to - a;
  if (dim == 2) d.z = 0;
  const double l2 = dot(d, d);
  const std::string t =
      dim == 2 ? fmt::format("(({}*({})+{}*({}))/({}))", dx, num(d.x), dy, num(d.y), num(l2))
               : fmt::format("(({}*({})+{}*({})+{}*({}))/({}))", dx, num(d.x), dy, num(d.y), dz,
                             num(d.z), num(l2));
  const std::string tc = fmt::format("(1-Max(0,1-Max(0,{})))", t);
  auto comp = [&](const std::string& e, double dk) { return fmt::format("({}-{}*({}))^2", e, tc, num(dk)); };
  return dim == 2 ? fmt::format("Sqrt({}+{})", comp(dx, d.x), comp(dy, d.y))
                  : fmt::format("Sqrt({}+{}+{})", comp(dx, d.x), comp(dy, d.y), comp(dz, d.z));
}

// A curved wall: the distance to it (expression) and its radius of curvature.
struct CurvedWall {
  std::string distance;
  double radius = 0;
};

// The curved walls of the body: circular holes (2D circles; 3D cylinder sides, through or
// drilled, their bottom rim included) and the cylinder's side. 2D slots are flat.
std::vector<CurvedWall> curved_walls(const GenerateSpec& s, const std::vector<HoleFrame>& frames,
                                     int dim) {
  std::vector<CurvedWall> walls;
  if (s.shape == "cylinder")
    walls.push_back({fmt::format("Abs(Sqrt((x-({}))^2+(y-({}))^2)-({}))", num(s.origin.x),
                                 num(s.origin.y), num(s.size.x)),
                     s.size.x});
  for (const HoleFrame& f : frames) {
    const std::string dx = fmt::format("(x-({}))", num(f.c.x)), dy = fmt::format("(y-({}))", num(f.c.y)),
                      dz = fmt::format("(z-({}))", num(f.c.z));
    if (dim == 2) {
      if (f.through)
        walls.push_back({fmt::format("Abs(Sqrt({}^2+{}^2)-({}))", dx, dy, num(f.r)), f.r});
      continue;
    }
    const std::string sa = fmt::format("({}*({})+{}*({})+{}*({}))", dx, num(f.a.x), dy, num(f.a.y),
                                       dz, num(f.a.z));  // along the axis from the collar
    const std::string rho = fmt::format("Sqrt(({}-{}*({}))^2+({}-{}*({}))^2+({}-{}*({}))^2)", dx,
                                        sa, num(f.a.x), dy, sa, num(f.a.y), dz, sa, num(f.a.z));
    if (f.through) {
      walls.push_back({fmt::format("Abs({}-({}))", rho, num(f.r)), f.r});
    } else {
      const std::string beyond = fmt::format("(Max(0,-{0})+Max(0,{0}-({1})))", sa, num(f.depth));
      walls.push_back({fmt::format("Sqrt(({}-({}))^2+{}^2)", rho, num(f.r), beyond), f.r});
    }
  }
  return walls;
}

}  // namespace

Mesh generate_mesh(const GenerateSpec& spec) {
  namespace occ = gmsh::model::occ;
  namespace field = gmsh::model::mesh::field;
  const Body body = check_spec(spec);
  const int dim = body.dim;
  const double tol = 1e-6 * body.extent;  // geometric tolerance of the face set tests
  const double ring_size = spec.ring_element_size > 0 ? spec.ring_element_size : spec.element_size;

  std::vector<HoleFrame> frames;
  for (const HoleSpec& h : spec.holes) frames.push_back(frame_of(h, dim));

  const std::string source = fmt::format("generated {} mesh", spec.shape);
  GmshSession session(source);
  try {
    gmsh::model::add("cdem_generate");

    // The body.
    gmsh::vectorpair solid;
    const Vec3 o = spec.origin, z = spec.size;
    if (spec.shape == "rectangle")
      solid = {{2, occ::addRectangle(o.x, o.y, 0, z.x, z.y)}};
    else if (spec.shape == "box")
      solid = {{3, occ::addBox(o.x, o.y, o.z, z.x, z.y, z.z)}};
    else
      solid = {{3, occ::addCylinder(o.x, o.y, o.z, 0, 0, z.z, z.x)}};

    // Empty holes are cut out.
    gmsh::vectorpair empty_tools;
    for (std::size_t i = 0; i < spec.holes.size(); ++i)
      if (spec.holes[i].region.empty()) empty_tools.push_back(make_hole_tool(frames[i], body));
    if (!empty_tools.empty()) {
      gmsh::vectorpair out;
      std::vector<gmsh::vectorpair> map;
      occ::cut(solid, empty_tools, out, map, -1, true, true);
      solid.clear();
      for (const auto& dt : out)
        if (dt.first == dim) solid.push_back(dt);
      if (solid.empty()) spec_error("the holes remove the whole body");
    }

    // Filled holes and the ring's inner part are clipped to the body, then fragmented with it.
    // owner[k]: which tool entity k comes from (hole index, or -1 for the ring's inner part).
    gmsh::vectorpair tools;
    std::vector<int> owner;
    for (std::size_t i = 0; i < spec.holes.size(); ++i) {
      if (spec.holes[i].region.empty()) continue;
      const gmsh::vectorpair part = clip_to_body(solid, make_hole_tool(frames[i], body));
      if (part.empty())
        spec_error(
            fmt::format("hole {} (region '{}') lies outside the body", i, spec.holes[i].region));
      for (const auto& dt : part) {
        tools.push_back(dt);
        owner.push_back(static_cast<int>(i));
      }
    }
    const bool ring = spec.ring_width > 0;
    if (ring) {
      const int inner = occ::addCylinder(o.x, o.y, o.z, 0, 0, z.z, z.x - spec.ring_width);
      for (const auto& dt : clip_to_body(solid, {3, inner})) {
        tools.push_back(dt);
        owner.push_back(-1);
      }
    }

    // Region of each top-dimension entity: the first filled hole containing it, else the main
    // region inside the ring's inner part, else "ring" (from the body only) when there is a ring.
    std::vector<std::pair<int, std::string>> entity_region;
    if (tools.empty()) {
      for (const auto& dt : solid) entity_region.emplace_back(dt.second, spec.region);
    } else {
      gmsh::vectorpair out;
      std::vector<gmsh::vectorpair> map;  // inputs: solid entities, then tools
      occ::fragment(solid, tools, out, map, -1, true, true);
      for (const auto& dt : out) {
        if (dt.first != dim) continue;
        int hole = -1;
        bool in_inner = false;
        for (std::size_t k = 0; k < tools.size(); ++k) {
          const auto& children = map[solid.size() + k];
          if (std::find(children.begin(), children.end(), dt) == children.end()) continue;
          if (owner[k] >= 0 && (hole < 0 || owner[k] < hole)) hole = owner[k];
          if (owner[k] < 0) in_inner = true;
        }
        std::string region = spec.region;
        if (hole >= 0)
          region = spec.holes[static_cast<std::size_t>(hole)].region;
        else if (ring && !in_inner)
          region = "ring";
        entity_region.emplace_back(dt.second, region);
      }
    }
    occ::synchronize();

    // Size field: the minimum of the global size (ring_element_size in the ring), each
    // refinement and (wall_sizing "refine") the curved walls' sizes.
    std::vector<double> fields;
    if (ring) {
      // element_size inside the ring's inner radius, ring_size beyond a short linear ramp
      // (half the smaller size) into the ring. Continuous on purpose: a step (Gmsh's Cylinder
      // field) right on the ring's inner wall makes the 1D meshing integrate the size field
      // at its discontinuity and take seconds.
      const int axis_dist = field::add("MathEval");
      field::setString(axis_dist, "F",
                       fmt::format("Sqrt((x-({}))^2+(y-({}))^2)", num(o.x), num(o.y)));
      const int base = field::add("Threshold");
      const double inner = z.x - spec.ring_width;
      field::setNumber(base, "IField", axis_dist);
      field::setNumber(base, "LcMin", spec.element_size);
      field::setNumber(base, "LcMax", ring_size);
      field::setNumber(base, "DistMin", inner);
      field::setNumber(base, "DistMax", inner + 0.5 * std::min(spec.element_size, ring_size));
      fields.push_back(base);
    } else {
      const int base = field::add("MathEval");
      field::setString(base, "F", num(spec.element_size));
      fields.push_back(base);
    }
    // Refinements: size r.size within r.radius of the point or segment, growing linearly to
    // element_size at refine_outer (no constraint beyond).
    std::vector<int> refine_dist;
    for (const RefineSpec& r : spec.refine) {
      const int dist = field::add("MathEval");
      field::setString(dist, "F", refine_distance(r, dim));
      refine_dist.push_back(dist);
      const int th = field::add("Threshold");
      field::setNumber(th, "IField", dist);
      field::setNumber(th, "LcMin", r.size);
      field::setNumber(th, "LcMax", spec.element_size);
      field::setNumber(th, "DistMin", r.radius);
      field::setNumber(th, "DistMax", refine_outer(r, spec.element_size));
      field::setNumber(th, "StopAtDistMax", 1);
      fields.push_back(th);
    }
    // Curved walls (holes, the cylinder) get at least circle_segments elements per full turn,
    // also where the hole is smaller than the element size: with the size field alone a 0.05 m
    // hole in a 0.1 m mesh is cut into 3-4 segments and a charge loses 40 % of its volume.
    // (n segments: the area of a circle is short by about (2 pi / n)^2 / 6: 2.6 % for 16.)
    // wall_sizing "finest": Gmsh's sizes from curvature, the smaller of them and the field wins.
    // "refine": the same rule from our own fields, W = 2 pi r / n on the wall growing by 1 m per
    // m away from it, and inside a refinement zone that zone's size wins over W (larger or
    // smaller: it is the size asked for there):
    //   size = Min(base, refinements, Max(Min(W), Max(Z))),
    // Z_j = r_j.size inside zone j, falling linearly to 0 over its graded band (0 beyond), so
    // Max(W, Z) = W outside every zone, >= the zone's size inside (the refinement then decides).
    const bool own_walls = spec.wall_sizing == "refine" && spec.circle_segments > 0;
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", own_walls ? 0 : std::max(0, spec.circle_segments));
    if (own_walls) {
      std::vector<double> wall_fields, zones;
      const double coarsest = std::max(spec.element_size, ring_size);
      for (const CurvedWall& w : curved_walls(spec, frames, dim)) {
        const double sc = 2 * std::numbers::pi * w.radius / spec.circle_segments;
        if (sc >= coarsest) continue;  // the field is finer everywhere anyway
        const int dist = field::add("MathEval");
        field::setString(dist, "F", w.distance);
        const int th = field::add("Threshold");
        field::setNumber(th, "IField", dist);
        field::setNumber(th, "LcMin", sc);
        field::setNumber(th, "LcMax", coarsest);
        field::setNumber(th, "DistMin", 0);
        field::setNumber(th, "DistMax", coarsest - sc);
        field::setNumber(th, "StopAtDistMax", 1);
        wall_fields.push_back(th);
      }
      for (std::size_t j = 0; j < spec.refine.size(); ++j) {
        const RefineSpec& r = spec.refine[j];
        const int zone = field::add("Threshold");
        field::setNumber(zone, "IField", refine_dist[j]);
        field::setNumber(zone, "LcMin", r.size);
        field::setNumber(zone, "LcMax", 0);
        field::setNumber(zone, "DistMin", r.radius);
        field::setNumber(zone, "DistMax", refine_outer(r, spec.element_size));
        zones.push_back(zone);
      }
      if (!wall_fields.empty()) {
        int w = static_cast<int>(wall_fields.front());
        if (wall_fields.size() > 1) {
          w = field::add("Min");
          field::setNumbers(w, "FieldsList", wall_fields);
        }
        if (!zones.empty()) {
          zones.push_back(w);
          w = field::add("Max");
          field::setNumbers(w, "FieldsList", zones);
        }
        fields.push_back(w);
      }
    }
    const int min_field = field::add("Min");
    field::setNumbers(min_field, "FieldsList", fields);
    field::setAsBackgroundMesh(min_field);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    gmsh::option::setNumber("General.NumThreads", 1);
    if (dim == 2 && spec.quads) {
      // Frontal-Delaunay triangles recombined into quadrilaterals by the blossom matching.
      // Not Mesh.Algorithm = 8 (Frontal-Delaunay for quads): in Gmsh 4.8.4 (Debian) it crashes
      // with a segmentation fault in backgroundMesh::getAngle even on a plain rectangle, which no
      // try/catch can turn into an error. Algorithm 6 + blossom gives as good quads here.
      gmsh::option::setNumber("Mesh.Algorithm", 6);
      gmsh::option::setNumber("Mesh.RecombinationAlgorithm", 1);  // blossom
      gmsh::option::setNumber("Mesh.RecombineAll", 1);
    }
    gmsh::model::mesh::generate(dim);
    session.check_log();

    // Regions: the main region first, then the holes' regions in hole order, then "ring".
    std::vector<std::string> region_order{spec.region};
    for (const HoleSpec& h : spec.holes)
      if (!h.region.empty()) region_order.push_back(h.region);
    if (ring) region_order.push_back("ring");
    int group = 0;
    for (std::size_t i = 0; i < region_order.size(); ++i) {
      const std::string& name = region_order[i];
      if (std::find(region_order.begin(), region_order.begin() + static_cast<long>(i), name) !=
          region_order.begin() + static_cast<long>(i))
        continue;
      std::vector<int> ents;
      for (const auto& [tag, region] : entity_region)
        if (region == name) ents.push_back(tag);
      if (ents.empty()) continue;
      gmsh::model::addPhysicalGroup(dim, ents, ++group);
      gmsh::model::setPhysicalName(dim, group, name);
    }

    // Face sets: a boundary entity belongs to a side when all its nodes lie on it; a hole's
    // wall is the part of the hole's boundary that is not on the outer boundary.
    const std::vector<Side> sides = outer_sides(spec, body, tol);
    std::vector<std::vector<int>> side_ents(sides.size()), hole_ents(frames.size());
    gmsh::vectorpair facets;
    gmsh::model::getEntities(facets, dim - 1);
    for (const auto& [fdim, ftag] : facets) {
      std::vector<std::size_t> ntags;
      std::vector<double> coord, param;
      gmsh::model::mesh::getNodes(ntags, coord, param, fdim, ftag, true, false);
      if (ntags.empty()) continue;
      auto all = [&](const auto& pred) {
        for (std::size_t k = 0; k < ntags.size(); ++k)
          if (!pred(Vec3{coord[3 * k], coord[3 * k + 1], coord[3 * k + 2]})) return false;
        return true;
      };
      bool outer = false;
      for (std::size_t i = 0; i < sides.size(); ++i)
        if (all(sides[i].on)) {
          side_ents[i].push_back(ftag);
          outer = true;
        }
      if (outer) continue;
      for (std::size_t h = 0; h < frames.size(); ++h)
        if (all([&](const Vec3& p) { return on_hole_boundary(frames[h], dim, p, tol); }))
          hole_ents[h].push_back(ftag);
    }
    group = 0;
    for (std::size_t i = 0; i < sides.size(); ++i) {
      if (side_ents[i].empty())
        spec_error(fmt::format("no boundary found for face set '{}'", sides[i].name));
      gmsh::model::addPhysicalGroup(dim - 1, side_ents[i], ++group);
      gmsh::model::setPhysicalName(dim - 1, group, sides[i].name);
    }
    for (std::size_t h = 0; h < frames.size(); ++h) {
      if (hole_ents[h].empty())
        spec_error(fmt::format("hole {} does not cut into the body (it has no wall)", h));
      gmsh::model::addPhysicalGroup(dim - 1, hole_ents[h], ++group);
      gmsh::model::setPhysicalName(dim - 1, group, fmt::format("hole{}", h));
    }

    Mesh mesh = detail::extract_gmsh_model(source);
    session.check_log();
    return mesh;
  } catch (...) {
    session.rethrow_as_mesh_error();
  }
}

}  // namespace cdem
