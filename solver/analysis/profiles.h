// Line profiles (outputs.profiles): the final fields sampled at equally
// spaced points of straight lines, e.g. the radial stress around a growing
// tumour. Everything is read from the Solution (reference node positions,
// connectivity, displacement, element fields), so every analysis type and
// element type is served alike. Lengths in mm, stresses in Pa.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "pba/scene.h"
#include "pba/solve.h"
#include "pba/status.h"

namespace pba {

// The number of points of a profile: its `points`, or 50 when that is 0.
int ProfilePointCount(const ProfileSpec& profile);

// Finds the element that holds a point of the reference configuration.
// Every element's bounding box is binned into a uniform grid of cells about
// one mean element wide, so a query tests only the few elements whose boxes
// cover its cell: building is linear in the elements, a query independent of
// their number (1e5 tetrahedra and 1000 points: about 0.03 s).
// The exact test uses the element's own geometry: barycentric coordinates
// for a 4-node tetrahedron, the inverse of the isoparametric map (Newton)
// for a 10-node tetrahedron (so curved faces count) and an 8-node brick.
class ElementLocator {
 public:
  // `nodes_mm`: nodes x 3 [mm]; `elements`: elements x nodes_per_element
  // node indices in the Solution's layout (4, 10 or 8 per element). Both
  // are kept by reference and must outlive the locator.
  ElementLocator(const std::vector<double>& nodes_mm, const std::vector<int64_t>& elements,
                 int nodes_per_element);

  struct Hit {
    int64_t element = -1;
    Eigen::Vector3d xi = Eigen::Vector3d::Zero();  // natural coordinates of the point
  };

  // Every element holding `x_mm`, in ascending order, with the point's
  // natural coordinates in each (tetrahedra: r, s, t, the volume
  // coordinates L1..L3; bricks: in [-1, 1]^3); none when it lies in no
  // element. A point on a face (within 1e-7 in natural coordinates) counts as
  // inside, so a point on a face, edge or node shared by several elements
  // is held by all of them.
  std::vector<Hit> LocateAll(const Eigen::Vector3d& x_mm) const;

  // The first element of LocateAll, or -1.
  int64_t Locate(const Eigen::Vector3d& x_mm, Eigen::Vector3d* xi) const;

  // The element's shape functions at natural point `xi`, one per node.
  Eigen::VectorXd ShapeFunctions(const Eigen::Vector3d& xi) const;

  int64_t num_elements() const { return num_elements_; }

 private:
  bool Inside(int64_t e, const Eigen::Vector3d& x, Eigen::Vector3d* xi) const;
  Eigen::Vector3d Node(int64_t e, int a) const;

  const std::vector<double>& nodes_;
  const std::vector<int64_t>& elements_;
  int per_element_ = 4;
  int64_t num_elements_ = 0;
  std::vector<float> boxes_;  // elements x 6: min x y z, max x y z (padded) [mm]
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double cell_mm_ = 1;
  std::array<int64_t, 3> dims_{0, 0, 0};
  std::vector<int64_t> cell_start_;     // cells + 1 offsets into cell_elements_
  std::vector<int64_t> cell_elements_;  // element indices, ascending per cell
};

// Samples every line of `profiles` (outputs.profiles) from `solution` (fields at
// the end of the analysis) into one table each, in order. Columns:
// distance_mm, x_mm, y_mm, z_mm (the point, reference configuration),
// ux_mm, uy_mm, uz_mm (displacement interpolated with the element's shape
// functions), and of the element holding the point (its one, or
// volume-averaged, value; a point on a face, edge or node shared by several
// elements takes the mean over them, so a line along element boundaries
// is not biased to one side): stress_along_pa = t . sigma . t with t the unit
// direction from from_mm to to_mm and sigma the Cauchy stress,
// mean_stress_pa = tr(sigma) / 3, von_mises_pa, and strain_along = t . e . t
// with e the Euler-Almansi strain of a finite-strain analysis or the small
// strain of a linear one. A point in no element has NaN past its position.
// Returns kInternal when the solution's connectivity is malformed.
Status SampleProfiles(const std::vector<ProfileSpec>& profiles, const Solution& solution,
                      std::vector<ProfileTable>* tables);

// Per table: points, points inside, the largest |stress_along_pa| and where.
std::vector<ProfileSummary> SummariseProfiles(const std::vector<ProfileTable>& tables);

}  // namespace pba
