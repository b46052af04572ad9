#include "atlas/label_mesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/lloyd_optimize_mesh_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/odt_optimize_mesh_3.h>
#include <CGAL/perturb_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <unordered_map>
#include <utility>

#include "mesh/quality.h"
#include "mesh/region_faces.h"

namespace pba {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
using VertexHandle = Triangulation::Vertex_handle;

constexpr double kMetresPerMm = 1e-3;

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

constexpr const char* kNoRegionMessage =
    "no region found inside the box: the labelling function is 0 everywhere the mesher "
    "sampled it (check the box, and that regions are not thinner than the facet size)";

// Seeds the triangulation with points on every surface and interface: the
// label is sampled on a grid of spacing about `spacing` [mm] over the box,
// and where it changes between neighbouring grid points the crossing is
// found by bisection (the domain's intersection construction) and inserted
// as a surface vertex, unless a seed already lies within `spacing`.
// CGAL's own initialisation shoots random rays from one centre and finds
// one crossing per ray, so a surface hidden behind another (the shell's
// outer sphere behind the core's) may get no seed, and Delaunay refinement
// never discovers a surface no seed touches: its region would be missing.
// Returns the number of seeds; 0 when the label is the same (0) at every
// grid point.
int InsertSurfaceSeeds(const Domain& domain, const Domain::Fct& function, const LabelMeshOptions& o,
                       double spacing, Complex* c3t3) {
  const Eigen::Vector3d extent = o.box_max_mm - o.box_min_mm;
  Eigen::Array3i n;  // grid points per axis
  for (int c = 0; c < 3; ++c)
    n[c] = std::max(2, static_cast<int>(std::ceil(extent[c] / spacing)) + 1);
  const Eigen::Vector3d step = extent.array() / (n - 1).cast<double>();
  const auto point = [&](int i, int j, int k) {
    const Eigen::Vector3d x = o.box_min_mm + step.cwiseProduct(Eigen::Vector3d(i, j, k));
    return Kernel::Point_3(x.x(), x.y(), x.z());
  };
  const auto flat = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * n[1] + j) * n[0] + i;
  };
  std::vector<int> labels(static_cast<std::size_t>(n.prod()));
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) labels[flat(i, j, k)] = function(point(i, j, k));
    }
  }

  // Seeds kept so far, hashed by the cell of side `spacing` they fall in.
  std::map<std::array<long, 3>, std::vector<Kernel::Point_3>> kept;
  const auto cell_of = [&](const Kernel::Point_3& p) {
    return std::array<long, 3>{std::lround(std::floor(p.x() / spacing)),
                               std::lround(std::floor(p.y() / spacing)),
                               std::lround(std::floor(p.z() / spacing))};
  };
  const auto crowded = [&](const Kernel::Point_3& p, double radius) {
    const std::array<long, 3> c = cell_of(p);
    for (long dz = -1; dz <= 1; ++dz) {
      for (long dy = -1; dy <= 1; ++dy) {
        for (long dx = -1; dx <= 1; ++dx) {
          const auto it = kept.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == kept.end()) continue;
          for (const Kernel::Point_3& q : it->second) {
            if (CGAL::squared_distance(p, q) < radius * radius) return true;
          }
        }
      }
    }
    return false;
  };

  const auto construct_intersection = domain.construct_intersection_object();
  const auto weighted = c3t3->triangulation().geom_traits().construct_weighted_point_3_object();
  int seeds = 0;
  const int offsets[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        for (const auto& d : offsets) {
          const int i2 = i + d[0], j2 = j + d[1], k2 = k + d[2];
          if (i2 >= n[0] || j2 >= n[1] || k2 >= n[2]) continue;
          if (labels[flat(i, j, k)] == labels[flat(i2, j2, k2)]) continue;
          const auto crossing =
              construct_intersection(Kernel::Segment_3(point(i, j, k), point(i2, j2, k2)));
          if (std::get<2>(crossing) != 2) continue;  // no surface point found
          const Kernel::Point_3& p = std::get<0>(crossing);
          if (crowded(p, spacing)) continue;
          kept[cell_of(p)].push_back(p);
          const VertexHandle v = c3t3->triangulation().insert(weighted(p));
          if (v == VertexHandle()) continue;  // hidden: cannot happen with zero weights
          c3t3->set_dimension(v, 2);
          c3t3->set_index(v, std::get<1>(crossing));
          ++seeds;
        }
      }
    }
  }
  // From each interior point, along the six axis directions to the first
  // change of label: a seed on a surface of the point's region even when the
  // grid above stepped over the region. Thinned like the grid's seeds, but
  // to half the region's own facet size (it may be smaller than `spacing`).
  const double walk_step = spacing / 16;
  const double reach = extent.norm();
  for (const Eigen::Vector3d& start : o.interior_points_mm) {
    const Kernel::Point_3 p0(start.x(), start.y(), start.z());
    const int inside = function(p0);
    if (inside == 0) continue;
    double radius = spacing / 2;
    if (inside <= static_cast<int>(o.region_facet_size_mm.size()) &&
        o.region_facet_size_mm[inside - 1] > 0) {
      radius = std::min(radius, o.region_facet_size_mm[inside - 1] / 2);
    }
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        Eigen::Vector3d direction = Eigen::Vector3d::Zero();
        direction[axis] = sign;
        Eigen::Vector3d previous = start;
        for (double t = walk_step; t <= reach; t += walk_step) {
          const Eigen::Vector3d x = start + t * direction;
          if (function(Kernel::Point_3(x.x(), x.y(), x.z())) == inside) {
            previous = x;
            continue;
          }
          const auto crossing = construct_intersection(
              Kernel::Segment_3(Kernel::Point_3(previous.x(), previous.y(), previous.z()),
                                Kernel::Point_3(x.x(), x.y(), x.z())));
          if (std::get<2>(crossing) == 2) {
            const Kernel::Point_3& p = std::get<0>(crossing);
            if (!crowded(p, radius)) {
              kept[cell_of(p)].push_back(p);
              const VertexHandle v = c3t3->triangulation().insert(weighted(p));
              if (v != VertexHandle()) {
                c3t3->set_dimension(v, 2);
                c3t3->set_index(v, std::get<1>(crossing));
                ++seeds;
              }
            }
          }
          break;
        }
      }
    }
  }
  return seeds;
}

Status ValidateOptions(const std::vector<std::string>& region_names, const LabelMeshOptions& o) {
  if (region_names.empty())
    return Status::InvalidArgument("region_names", "at least one region name is needed");
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(o.box_min_mm[c]) || !std::isfinite(o.box_max_mm[c]))
      return Status::InvalidArgument("box_min_mm", "the bounding box must be finite");
    if (!(o.box_max_mm[c] > o.box_min_mm[c])) {
      return Status::InvalidArgument(
          "box_max_mm", "the bounding box is empty or inverted along axis " + std::to_string(c) +
                            " (max " + std::to_string(o.box_max_mm[c]) + " <= min " +
                            std::to_string(o.box_min_mm[c]) + ")");
    }
  }
  if (!(o.cell_size_mm > 0) || !std::isfinite(o.cell_size_mm))
    return Status::InvalidArgument("cell_size_mm", "must be positive");
  if (!(o.facet_size_mm >= 0) || !std::isfinite(o.facet_size_mm))
    return Status::InvalidArgument("facet_size_mm", "must be positive (or 0 for the cell size)");
  if (!(o.roi_radius_mm >= 0) || !std::isfinite(o.roi_radius_mm))
    return Status::InvalidArgument("roi_radius_mm",
                                   "must be 0 (no region of interest) or positive");
  if (!(o.roi_transition_mm >= 0) || !std::isfinite(o.roi_transition_mm))
    return Status::InvalidArgument("roi_transition_mm", "must be 0 (the radius) or positive");
  if (o.roi_radius_mm > 0 && !(o.roi_size_mm > 0 && o.roi_size_mm <= o.cell_size_mm))
    return Status::InvalidArgument("roi_size_mm", "must be positive and at most cell_size_mm");
  if (!o.roi_centre_mm.allFinite())
    return Status::InvalidArgument("roi_centre_mm", "must be finite");
  if (!(o.facet_distance_mm >= 0) || !std::isfinite(o.facet_distance_mm)) {
    return Status::InvalidArgument("facet_distance_mm",
                                   "must be positive (or 0 for a tenth of the facet size)");
  }
  if (!(o.facet_angle_deg > 0 && o.facet_angle_deg <= 30)) {
    return Status::InvalidArgument("facet_angle_deg",
                                   "must lie in (0, 30]: refinement may not end above 30");
  }
  if (!(o.cell_radius_edge_ratio >= 2) || !std::isfinite(o.cell_radius_edge_ratio)) {
    return Status::InvalidArgument("cell_radius_edge_ratio",
                                   "must be at least 2: refinement may not end below 2");
  }
  if (o.odt_iterations < 0) return Status::InvalidArgument("odt_iterations", "must be >= 0");
  if (o.lloyd_iterations < 0) return Status::InvalidArgument("lloyd_iterations", "must be >= 0");
  if (!(o.optimisation_time_limit_s >= 0)) {
    return Status::InvalidArgument("optimisation_time_limit_s", "must be >= 0 (0: no limit)");
  }
  if ((o.exude || o.perturb) && !(o.sliver_bound_deg > 0 && o.sliver_bound_deg < 70.5)) {
    return Status::InvalidArgument("sliver_bound_deg",
                                   "must lie in (0, 70.5): a regular tetrahedron's is 70.53");
  }
  for (const auto& [name, sizes] : {std::pair<const char*, const std::vector<double>*>{
                                        "region_facet_size_mm", &o.region_facet_size_mm},
                                    {"region_cell_size_mm", &o.region_cell_size_mm}}) {
    if (!sizes->empty() && sizes->size() != region_names.size()) {
      return Status::InvalidArgument(
          name, "has " + std::to_string(sizes->size()) + " entries for " +
                    std::to_string(region_names.size()) + " regions: give one per region, or none");
    }
    for (std::size_t r = 0; r < sizes->size(); ++r) {
      const double size = (*sizes)[r];
      if (!(size >= 0) || !std::isfinite(size)) {
        return Status::InvalidArgument(
            std::string(name) + "[" + std::to_string(r) + "]",
            "must be 0 (the global size) or positive, not " + std::to_string(size));
      }
    }
  }
  for (std::size_t i = 0; i < o.interior_points_mm.size(); ++i) {
    if (!o.interior_points_mm[i].allFinite())
      return Status::InvalidArgument("interior_points_mm[" + std::to_string(i) + "]",
                                     "must be finite");
  }
  if (!(o.relative_error_bound > 0 && o.relative_error_bound < 1))
    return Status::InvalidArgument("relative_error_bound", "must lie in (0, 1)");
  return Status::Ok();
}

// The tetrahedra of the complex as a pba::Mesh (see MeshLabels).
Status ConvertComplex(const Complex& c3t3, const std::vector<std::string>& region_names,
                      Mesh* mesh) {
  const int num_regions = static_cast<int>(region_names.size());
  std::unordered_map<const void*, int> node_of;  // vertex address -> node
  std::vector<Eigen::Vector3d> points;
  Mesh out;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    const int label = c3t3.subdomain_index(c);
    if (label < 0) {
      return Status::InvalidArgument("label", "the labelling function returned label " +
                                                  std::to_string(label) +
                                                  ": labels are 0 (outside) or positive");
    }
    if (label > num_regions) {
      return Status::InvalidArgument(
          "region_names", "the labelling function returned label " + std::to_string(label) +
                              ", which has no name: there are " + std::to_string(num_regions) +
                              " region names, for labels 1.." + std::to_string(num_regions));
    }
    std::array<int, 4> tet{};
    for (int i = 0; i < 4; ++i) {
      const VertexHandle v = c->vertex(i);
      const auto [it, added] = node_of.emplace(&*v, static_cast<int>(points.size()));
      if (added) {
        const auto& p = v->point();  // weighted after exudation; the weight is not needed
        points.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
      }
      tet[i] = it->second;
    }
    const Eigen::Vector3d a = points[tet[1]] - points[tet[0]];
    const Eigen::Vector3d b = points[tet[2]] - points[tet[0]];
    const Eigen::Vector3d d = points[tet[3]] - points[tet[0]];
    if (a.dot(b.cross(d)) < 0) std::swap(tet[2], tet[3]);
    out.tets.push_back(tet);
    out.element_region.push_back(label - 1);
  }
  if (out.tets.empty()) {
    return Status::FailedPrecondition(kNoRegionMessage);
  }

  out.nodes.resize(static_cast<int>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    out.nodes.row(static_cast<int>(i)) = kMetresPerMm * points[i].transpose();
  out.region_names = region_names;

  // Boundary and interface triangles, from the tetrahedra themselves, so
  // that the sets always match the elements (mesh/region_faces.h).
  RebuildRegionFaceSets(&out);
  *mesh = std::move(out);
  return Status::Ok();
}

// The size bound at a point: `coarse` away from the region of interest,
// options.roi_size_mm (or `coarse` if smaller) inside it, linear between
// (see LabelMeshOptions); on a surface patch (dimension 2) at most the
// regions' own facet bound, scaled by `scale` (1 for the facet size, facet
// distance / facet size for the distance); for the cell size (scale 0)
// inside a region (dimension 3) at most the region's own cell bound.
struct SizeField {
  using FT = Kernel::FT;  // CGAL's MeshDomainField_3
  using Point_3 = Kernel::Point_3;
  using Index = Domain::Index;
  const LabelMeshOptions& options;
  double coarse;
  double scale = 0;  // 0: the cell size field
  double operator()(const Kernel::Point_3& p, int dimension, const Domain::Index& index) const {
    double bound = coarse;
    if (scale > 0 && dimension == 2 && !options.region_facet_size_mm.empty()) {
      if (const auto* patch = boost::get<Domain::Surface_patch_index>(&index)) {
        for (const int region : {patch->first, patch->second}) {
          if (region < 1 || region > static_cast<int>(options.region_facet_size_mm.size()))
            continue;
          const double own = options.region_facet_size_mm[region - 1];
          if (own > 0) bound = std::min(bound, scale * own);
        }
      }
    }
    if (scale == 0 && dimension == 3 && !options.region_cell_size_mm.empty()) {
      if (const auto* region = boost::get<Domain::Subdomain_index>(&index)) {
        if (*region >= 1 && *region <= static_cast<int>(options.region_cell_size_mm.size())) {
          const double own = options.region_cell_size_mm[*region - 1];
          if (own > 0) bound = std::min(bound, own);
        }
      }
    }
    if (options.roi_radius_mm <= 0) return bound;
    const double fine = std::min(options.roi_size_mm * (scale > 0 ? scale : 1), bound);
    const double transition =
        options.roi_transition_mm > 0 ? options.roi_transition_mm : options.roi_radius_mm;
    const double d = (Eigen::Vector3d(p.x(), p.y(), p.z()) - options.roi_centre_mm).norm() -
                     options.roi_radius_mm;
    if (d <= 0) return fine;
    return std::min(bound, fine + (bound - fine) * d / transition);
  }
};

}  // namespace

Status MeshLabels(const LabelFunction& label, const std::vector<std::string>& region_names,
                  const LabelMeshOptions& options, Mesh* mesh, LabelMeshReport* report) {
  if (!label) return Status::InvalidArgument("label", "no labelling function given");
  PBA_RETURN_IF_ERROR(ValidateOptions(region_names, options));
  const double facet_size =
      options.facet_size_mm > 0 ? options.facet_size_mm : options.cell_size_mm;
  const double facet_distance =
      options.facet_distance_mm > 0 ? options.facet_distance_mm : facet_size / 10;

  try {
    namespace params = CGAL::parameters;
    // The wrapper returns 0 on and outside the box's faces (within a
    // billionth of its diagonal), so that a region reaching them is closed
    // there rather than left open. A label CGAL sees as a region but that
    // has no name is reported after meshing (ConvertComplex), with the label
    // in the message.
    const double margin = 1e-9 * (options.box_max_mm - options.box_min_mm).norm();
    const Eigen::Vector3d inner_min = options.box_min_mm.array() + margin;
    const Eigen::Vector3d inner_max = options.box_max_mm.array() - margin;
    Domain::Fct function = [&](const Kernel::Point_3& p) {
      const Eigen::Vector3d x(p.x(), p.y(), p.z());
      if ((x.array() <= inner_min.array()).any() || (x.array() >= inner_max.array()).any())
        return 0;
      return label(x);
    };
    const Kernel::Iso_cuboid_3 box(options.box_min_mm.x(), options.box_min_mm.y(),
                                   options.box_min_mm.z(), options.box_max_mm.x(),
                                   options.box_max_mm.y(), options.box_max_mm.z());
    CGAL::Random random(options.seed);
    // CGAL's own default generator too (initial points, random shooting):
    // the same inputs give the same mesh in every process.
    CGAL::get_default_random() = CGAL::Random(options.seed);
    const Domain domain(function, box, options.relative_error_bound, CGAL::Null_subdomain_index(),
                        &random);
    const SizeField cell_size{options, options.cell_size_mm};
    const SizeField facet_size_field{options, facet_size, 1};
    const SizeField facet_distance_field{options, facet_distance, facet_distance / facet_size};
    const Criteria criteria(params::facet_angle = options.facet_angle_deg,
                            params::facet_size = facet_size_field,
                            params::facet_distance = facet_distance_field,
                            params::cell_radius_edge_ratio = options.cell_radius_edge_ratio,
                            params::cell_size = cell_size);
    // An explicit time limit: CGAL's default (the refinement's own running
    // time) would make every result depend on the machine's load. The
    // sliver bound and the iteration counts usually end each step well
    // before it. The steps run one by one, in make_mesh_3's order, so each
    // is timed and its outcome known.
    const double bound = options.sliver_bound_deg;
    const double limit = options.optimisation_time_limit_s;
    LabelMeshReport local_report;
    LabelMeshReport& r = report != nullptr ? *report : local_report;
    r = LabelMeshReport();
    Clock::time_point start = Clock::now();
    Complex c3t3;
    if (InsertSurfaceSeeds(domain, function, options, facet_size, &c3t3) == 0)
      return Status::FailedPrecondition(kNoRegionMessage);
    // Too few seeds to span a tetrahedron (a region about one facet size
    // across): add CGAL's random surface points, as make_mesh_3 would.
    if (c3t3.triangulation().dimension() != 3)
      CGAL::Mesh_3::internal::init_c3t3(c3t3, domain, criteria, 20);
    r.seed_s = SecondsSince(start);
    start = Clock::now();
    CGAL::refine_mesh_3(c3t3, domain, criteria, params::no_odt(), params::no_lloyd(),
                        params::no_perturb(), params::no_exude(), params::no_reset_c3t3());
    r.refine_s = SecondsSince(start);
    const auto note = [&](const char* step, CGAL::Mesh_optimization_return_code code) {
      if (code == CGAL::TIME_LIMIT_REACHED) r.time_limit_reached.push_back(step);
    };
    // CGAL stops ODT and Lloyd early when fewer than `freeze_bound` of the
    // vertices move (relative to their edges), or when the moves get below
    // `convergence`; both at CGAL's defaults.
    if (options.odt_iterations > 0) {
      start = Clock::now();
      note("odt", CGAL::odt_optimize_mesh_3(c3t3, domain, params::time_limit = limit,
                                            params::max_iteration_number = options.odt_iterations));
      r.odt_s = SecondsSince(start);
    }
    if (options.lloyd_iterations > 0) {
      start = Clock::now();
      note("lloyd",
           CGAL::lloyd_optimize_mesh_3(c3t3, domain, params::time_limit = limit,
                                       params::max_iteration_number = options.lloyd_iterations));
      r.lloyd_s = SecondsSince(start);
    }
    if (options.perturb) {
      start = Clock::now();
      note("perturb", CGAL::perturb_mesh_3(c3t3, domain, params::time_limit = limit,
                                           params::sliver_bound = bound));
      r.perturb_s = SecondsSince(start);
    }
    if (options.exude) {
      // In slices of a second, stopped when one does not improve the mesh:
      // CGAL 5.5's exuder can go on pumping weights without raising any
      // angle until its time limit (two structures of the synthetic atlas
      // at 4 mm: docs/atlas.md). Improvement: a larger smallest dihedral angle, or fewer
      // tetrahedra below the sliver bound.
      start = Clock::now();
      const auto state = [&c3t3, bound] {
        double smallest = 180;
        int64_t slivers = 0;
        for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
          Eigen::Matrix<double, 4, 3> x;
          for (int i = 0; i < 4; ++i) {
            const auto& p = c->vertex(i)->point();
            x.row(i) << CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z());
          }
          const double angle = TetDihedralRangeDegrees(x)[0];
          smallest = std::min(smallest, angle);
          slivers += angle < bound;
        }
        return std::make_pair(smallest, slivers);
      };
      constexpr double kSliceS = 1;
      auto before = state();
      for (;;) {
        const double left = limit > 0 ? limit - SecondsSince(start) : kSliceS;
        if (left <= 0) {
          r.time_limit_reached.push_back("exude");
          break;
        }
        const CGAL::Mesh_optimization_return_code code = CGAL::exude_mesh_3(
            c3t3, params::time_limit = std::min(kSliceS, left), params::sliver_bound = bound);
        if (code != CGAL::TIME_LIMIT_REACHED) break;
        const auto after = state();
        if (!(after.first > before.first || after.second < before.second)) break;
        before = after;
      }
      r.exude_s = SecondsSince(start);
    }
    return ConvertComplex(c3t3, region_names, mesh);
  } catch (const std::exception& e) {
    return Status::Internal(std::string("CGAL meshing failed: ") + e.what());
  } catch (...) {
    return Status::Internal("CGAL meshing failed with an unknown exception");
  }
}

}  // namespace pba
