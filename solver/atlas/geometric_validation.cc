#include "atlas/geometric_validation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "atlas/distance_transform.h"
#include "core/format.h"

namespace pba {
namespace {

constexpr double kMmPerM = 1000.0;

using Box = PixelBox;

Status ValidateInputs(const Mesh& mesh, const std::vector<uint16_t>& region_label,
                      const PlateStack& plates) {
  PBA_RETURN_IF_ERROR(ValidateLabelledTetMesh(mesh, region_label, "region_label", "validation"));
  return ValidatePlateStack(plates, "plates", 1);
}

// The mesh cut at height z [mm] on the plates' pixel grid: per pixel the
// label of the tetrahedron containing its centre, 0 if none.
std::vector<uint16_t> RasteriseSection(const Mesh& mesh, const std::vector<uint16_t>& tet_label,
                                       const std::vector<std::array<float, 2>>& z_range,
                                       const PlateStack& plates, double z) {
  const int w = plates.width, h = plates.height;
  const double ps = plates.pixel_size_mm, ox = plates.origin_mm.x(), oy = plates.origin_mm.y();
  std::vector<uint16_t> section(static_cast<size_t>(w) * h, 0);
  constexpr double kTolerance = 1e-9;
  for (size_t e = 0; e < mesh.tets.size(); ++e) {
    if (tet_label[e] == 0 || z < z_range[e][0] - 1e-6 || z > z_range[e][1] + 1e-6) continue;
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, static_cast<int>(e)) * kMmPerM;
    Eigen::Matrix3d edges;
    for (int k = 0; k < 3; ++k) edges.col(k) = (x.row(k + 1) - x.row(0)).transpose();
    const double det = edges.determinant();
    if (!(std::abs(det) > 0)) continue;  // a flat element holds no pixel centre
    const Eigen::Matrix3d inverse = edges.inverse();
    const Eigen::Vector3d lo = x.colwise().minCoeff(), hi = x.colwise().maxCoeff();
    const int c0 = std::max(0, static_cast<int>(std::ceil((lo.x() - ox) / ps - kTolerance)));
    const int c1 = std::min(w - 1, static_cast<int>(std::floor((hi.x() - ox) / ps + kTolerance)));
    const int r0 = std::max(0, static_cast<int>(std::ceil((oy - hi.y()) / ps - kTolerance)));
    const int r1 = std::min(h - 1, static_cast<int>(std::floor((oy - lo.y()) / ps + kTolerance)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const Eigen::Vector3d p(ox + c * ps, oy - r * ps, z);
        const Eigen::Vector3d l = inverse * (p - x.row(0).transpose());
        if (l.minCoeff() >= -kTolerance && l.sum() <= 1 + kTolerance) {
          section[static_cast<size_t>(r) * w + c] = tet_label[e];
        }
      }
    }
  }
  return section;
}

// Per label, the bounding box of its pixels.
std::map<uint16_t, Box> LabelBoxes(const std::vector<uint16_t>& image, int w, int h) {
  std::vector<Box> boxes(65536);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const uint16_t l = image[static_cast<size_t>(r) * w + c];
      if (l != 0) boxes[l].Add(c, r);
    }
  }
  std::map<uint16_t, Box> present;
  for (int l = 1; l < 65536; ++l) {
    if (!boxes[l].empty()) present[static_cast<uint16_t>(l)] = boxes[l];
  }
  return present;
}

// One image's view of one label over a box: membership, boundary pixels
// (4-neighbour of another label, outside the image as background).
struct LabelMask {
  std::vector<uint8_t> in, boundary;
  int count = 0, boundary_count = 0;
};

LabelMask MakeMask(const std::vector<uint16_t>& image, int w, int h, uint16_t label,
                   const Box& box) {
  const auto is = [&](int c, int r) {
    return c >= 0 && r >= 0 && c < w && r < h && image[static_cast<size_t>(r) * w + c] == label;
  };
  LabelMask m;
  const int bw = box.width(), bh = box.height();
  m.in.assign(static_cast<size_t>(bw) * bh, 0);
  m.boundary.assign(m.in.size(), 0);
  for (int r = 0; r < bh; ++r) {
    for (int c = 0; c < bw; ++c) {
      const int ic = box.c0 + c, ir = box.r0 + r;
      if (!is(ic, ir)) continue;
      const size_t i = static_cast<size_t>(r) * bw + c;
      m.in[i] = 1;
      ++m.count;
      if (!is(ic - 1, ir) || !is(ic + 1, ir) || !is(ic, ir - 1) || !is(ic, ir + 1)) {
        m.boundary[i] = 1;
        ++m.boundary_count;
      }
    }
  }
  return m;
}

// Marching-squares contour length of the mask [pixels]: the cells between
// pixel centres, including the ring of cells half outside the box (the box
// holds every pixel of the label, so the contour closes there).
double ContourLength(const LabelMask& m, const Box& box) {
  const int bw = box.width(), bh = box.height();
  const auto in = [&](int c, int r) {
    return c >= 0 && r >= 0 && c < bw && r < bh && m.in[static_cast<size_t>(r) * bw + c];
  };
  const double half_diagonal = std::sqrt(0.5);
  double length = 0;
  for (int r = -1; r < bh; ++r) {
    for (int c = -1; c < bw; ++c) {
      const bool a = in(c, r), b = in(c + 1, r), d = in(c, r + 1), e = in(c + 1, r + 1);
      const int n = a + b + d + e;
      if (n == 1 || n == 3) {
        length += half_diagonal;
      } else if (n == 2) {
        length += (a == e) ? 2 * half_diagonal : 1.0;  // diagonal pair: a saddle, two cuts
      }
    }
  }
  return length;
}

// Mean distance [pixels] from the boundary pixels of `from` to the nearest
// boundary pixel of `to`.
double MeanBoundaryDistance(const LabelMask& from, const LabelMask& to, const Box& box) {
  std::vector<double> squared;
  SquaredDistanceTransform2d(to.boundary, box.width(), box.height(), &squared);
  double sum = 0;
  for (size_t i = 0; i < squared.size(); ++i) {
    if (from.boundary[i]) sum += std::sqrt(squared[i]);
  }
  return sum / from.boundary_count;
}

// Mean distance [pixels] from the boundary pixels of m to the centroid of
// their own 8-connected piece of m: each piece shrunk to its centre (a
// bilateral structure's centroid lies between the hemispheres, far from
// either piece).
double MeanRadius(const LabelMask& m, const Box& box) {
  const int bw = box.width(), bh = box.height();
  std::vector<int> piece(m.in.size(), -1);
  std::vector<Eigen::Vector3d> sums;  // per piece: sum of c, sum of r, count
  std::vector<int> todo;
  for (size_t seed = 0; seed < m.in.size(); ++seed) {
    if (!m.in[seed] || piece[seed] >= 0) continue;
    const int id = static_cast<int>(sums.size());
    sums.push_back(Eigen::Vector3d::Zero());
    piece[seed] = id;
    todo.assign(1, static_cast<int>(seed));
    while (!todo.empty()) {
      const int i = todo.back();
      todo.pop_back();
      const int c = i % bw, r = i / bw;
      sums[id] += Eigen::Vector3d(c, r, 1);
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int nc = c + dc, nr = r + dr;
          if (nc < 0 || nr < 0 || nc >= bw || nr >= bh) continue;
          const int j = nr * bw + nc;
          if (!m.in[j] || piece[j] >= 0) continue;
          piece[j] = id;
          todo.push_back(j);
        }
      }
    }
  }
  double sum = 0;
  for (size_t i = 0; i < m.boundary.size(); ++i) {
    if (!m.boundary[i]) continue;
    const Eigen::Vector3d& s = sums[piece[i]];
    sum += std::hypot(static_cast<double>(i % bw) - s.x() / s.z(),
                      static_cast<double>(i / bw) - s.y() / s.z());
  }
  return sum / m.boundary_count;
}

// The sectional errors of every label on plate p.
std::vector<std::pair<uint16_t, SectionError>> PlateErrors(const PlateStack& plates, int p,
                                                           const std::vector<uint16_t>& section) {
  const int w = plates.width, h = plates.height;
  const double ps = plates.pixel_size_mm;
  const std::vector<uint16_t>& plate = plates.labels[p];
  const std::map<uint16_t, Box> on_plate = LabelBoxes(plate, w, h);
  const std::map<uint16_t, Box> in_section = LabelBoxes(section, w, h);
  std::map<uint16_t, Box> boxes = on_plate;
  for (const auto& [label, box] : in_section) boxes[label].Add(box);

  std::vector<std::pair<uint16_t, SectionError>> errors;
  for (const auto& [label, box] : boxes) {
    const LabelMask mp = MakeMask(plate, w, h, label, box);
    const LabelMask ms = MakeMask(section, w, h, label, box);
    SectionError s;
    s.plate = p;
    s.z_mm = plates.z_mm[p];
    s.landmarks = mp.boundary_count;
    s.section_landmarks = ms.boundary_count;
    s.in_plate = mp.count > 0;
    s.in_section = ms.count > 0;
    if (s.in_plate && s.in_section) {
      s.mean_distance_mm =
          0.5 * (MeanBoundaryDistance(mp, ms, box) + MeanBoundaryDistance(ms, mp, box)) * ps;
      s.perimeter_mm = ContourLength(mp, box) * ps;
    } else if (s.in_plate) {
      s.mean_distance_mm = MeanRadius(mp, box) * ps;
      s.perimeter_mm = ContourLength(mp, box) * ps;
    } else {
      s.mean_distance_mm = MeanRadius(ms, box) * ps;
      s.perimeter_mm = ContourLength(ms, box) * ps;
    }
    errors.emplace_back(label, s);
  }
  return errors;
}

}  // namespace

Status RegionLabelsFromNames(const Mesh& mesh, const ColourTable& colours,
                             std::vector<uint16_t>* region_label) {
  std::vector<uint16_t> labels;
  for (size_t r = 0; r < mesh.region_names.size(); ++r) {
    const ColourEntry* entry = colours.FindByName(mesh.region_names[r]);
    if (entry == nullptr) {
      return Status::InvalidArgument(
          Format("mesh.region_names[%zu]", r),
          "\"" + mesh.region_names[r] + "\" is not a structure of the colour table");
    }
    labels.push_back(entry->label);
  }
  *region_label = std::move(labels);
  return Status::Ok();
}

Status ValidateLabelledTetMesh(const Mesh& mesh, const std::vector<uint16_t>& labels,
                               const std::string& labels_field, const std::string& what) {
  switch (mesh.shape()) {
    case ElementShape::kTet4:
    case ElementShape::kTet10:
      break;  // the cuts use the corners
    case ElementShape::kHex8:
      return Status::InvalidArgument("mesh", "a hexahedral mesh; the " + what + " cuts tetrahedra");
  }
  if (mesh.tets.empty()) return Status::InvalidArgument("mesh", "no elements");
  if (!mesh.element_region.empty() && mesh.element_region.size() != mesh.tets.size()) {
    return Status::InvalidArgument(
        "mesh.element_region",
        Format("%zu entries for %zu elements", mesh.element_region.size(), mesh.tets.size()));
  }
  const size_t regions = std::max<size_t>(1, mesh.region_names.size());
  if (labels.size() != regions) {
    return Status::InvalidArgument(labels_field,
                                   Format("%zu labels for %zu regions", labels.size(), regions));
  }
  for (size_t e = 0; e < mesh.element_region.size(); ++e) {
    if (mesh.element_region[e] < 0 || static_cast<size_t>(mesh.element_region[e]) >= regions) {
      return Status::InvalidArgument(Format("mesh.element_region[%zu]", e),
                                     Format("region %d of %zu", mesh.element_region[e], regions));
    }
  }
  return Status::Ok();
}

Status ValidateAgainstPlates(const Mesh& mesh, const std::vector<uint16_t>& region_label,
                             const PlateStack& plates, const ThreadContext& threads,
                             GeometricValidation* out) {
  PBA_RETURN_IF_ERROR(ValidateInputs(mesh, region_label, plates));
  const size_t nt = mesh.tets.size();
  std::vector<uint16_t> tet_label(nt);
  std::vector<std::array<float, 2>> z_range(nt);
  for (size_t e = 0; e < nt; ++e) {
    tet_label[e] = region_label[mesh.element_region.empty() ? 0 : mesh.element_region[e]];
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (int n : mesh.tets[e]) {
      const float z = static_cast<float>(mesh.nodes(n, 2) * kMmPerM);
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
    z_range[e] = {lo, hi};
  }

  const int np = plates.num_plates();
  std::vector<std::vector<std::pair<uint16_t, SectionError>>> per_plate(np);
#pragma omp parallel for schedule(dynamic) num_threads(threads.threads())
  for (int p = 0; p < np; ++p) {
    const std::vector<uint16_t> section =
        RasteriseSection(mesh, tet_label, z_range, plates, plates.z_mm[p]);
    per_plate[p] = PlateErrors(plates, p, section);
  }

  // Every structure of the plates or the mesh, by label; sections by plate.
  std::map<uint16_t, StructureValidation> structures;
  for (uint16_t label : region_label) {
    if (label != 0) structures[label].label = label;
  }
  for (const auto& errors : per_plate) {
    for (const auto& [label, s] : errors) {
      structures[label].label = label;
      structures[label].sections.push_back(s);
    }
  }
  GeometricValidation result;
  double pooled_pe = 0, pooled_p = 0;
  for (auto& [label, v] : structures) {
    const ColourEntry* entry = plates.colours.FindByLabel(label);
    v.name = entry ? entry->name : Format("label %d", static_cast<int>(label));
    double pe = 0, sum_p = 0;
    for (const SectionError& s : v.sections) {
      pe += s.perimeter_mm * s.mean_distance_mm;
      sum_p += s.perimeter_mm;
    }
    const int n = static_cast<int>(v.sections.size());
    // A mesh region on no plate and in no section has nothing to compare:
    // E and %Err 0 with no sections.
    v.structural_error_mm = sum_p > 0 ? pe / sum_p : 0;                            // eq. 4.2
    v.percentage_error = sum_p > 0 ? v.structural_error_mm * n / sum_p * 100 : 0;  // eq. 4.3
    v.flagged = v.percentage_error > kGeometricErrorLimitPercent;
    pooled_pe += pe;
    pooled_p += sum_p;
    result.total_sections += n;
    result.structures.push_back(std::move(v));
  }
  result.overall_structural_error_mm = pooled_p > 0 ? pooled_pe / pooled_p : 0;
  result.overall_percentage_error =
      pooled_p > 0 ? result.overall_structural_error_mm * result.total_sections / pooled_p * 100
                   : 0;
  result.overall_flagged = result.overall_percentage_error > kGeometricErrorLimitPercent;
  *out = std::move(result);
  return Status::Ok();
}

ReportTable ValidationReportTable(const GeometricValidation& validation) {
  ReportTable table;
  table.title = Format("Geometric validation against the plates (eqs. 4.2, 4.3; limit %.2f %%)",
                       kGeometricErrorLimitPercent);
  table.columns = {{"structure", "structure", 0},   {"label", "label", 0},
                   {"sections", "sections", 0},     {"E [mm]", "structural_error_mm", 3},
                   {"%Err", "percentage_error", 3}, {"flag", "flagged", 0}};
  for (const StructureValidation& s : validation.structures) {
    table.rows.push_back({ReportCell::Text(s.name), ReportCell::Integer(s.label),
                          ReportCell::Integer(static_cast<int64_t>(s.sections.size())),
                          ReportCell::Real(s.structural_error_mm),
                          ReportCell::Real(s.percentage_error), ReportCell::Flag(s.flagged)});
  }
  table.footer = std::vector<ReportCell>{ReportCell::Text("overall"),
                                         ReportCell::Text(""),
                                         ReportCell::Integer(validation.total_sections),
                                         ReportCell::Real(validation.overall_structural_error_mm),
                                         ReportCell::Real(validation.overall_percentage_error),
                                         ReportCell::Flag(validation.overall_flagged)};
  return table;
}

std::string FormatValidationTable(const GeometricValidation& validation, TableFormat format) {
  return FormatReportTable(ValidationReportTable(validation), format);
}

}  // namespace pba
