// Abaqus/CalculiX input deck of a scene's model, so the same problem can be
// run in a peer code (CalculiX: `ccx -i model`). SI units: m, N, Pa.
#include "results/abaqus_writer.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#include "fem/element_kind.h"
#include "material/linear_elastic.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {
namespace {

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Abaqus reads at most 16 entries per data line.
void WriteIdList(std::ofstream& out, const std::vector<int>& nodes) {
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    out << nodes[i] + 1 << ((i % 16 == 15 || i + 1 == nodes.size()) ? "\n" : ", ");
  }
}

// Data lines of at most 8 values, each at most kAbaqusFieldWidth characters.
std::string DataLines(const std::vector<double>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    text += AbaqusNumber(values[i]);
    text += (i % 8 == 7 || i + 1 == values.size()) ? "\n" : ", ";
  }
  return text;
}

// *ELASTIC or *HYPERELASTIC cards in the Abaqus conventions, which PBA's
// models follow (C_ij, D_i = 2 / K, Ogden 2 mu / alpha^2).
std::string MaterialCards(const MaterialSpec& m) {
  switch (m.kind) {
    case MaterialSpec::Kind::kLinearElastic:
      return "*ELASTIC\n" +
             DataLines({m.linear_elastic.youngs_modulus_pa, m.linear_elastic.poissons_ratio});
    case MaterialSpec::Kind::kOrthotropicElastic: {
      // Abaqus order: E1 E2 E3 nu12 nu13 nu23 G12 G13 on the first line, G23
      // on the second; nu_ij means -eps_j / eps_i there too.
      const OrthotropicElasticParams& p = m.orthotropic_elastic;
      return "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n" +
             DataLines(
                 {p.e1_pa, p.e2_pa, p.e3_pa, p.nu12, p.nu13, p.nu23, p.g12_pa, p.g13_pa, p.g23_pa});
    }
    case MaterialSpec::Kind::kNeoHookean:
      return "*HYPERELASTIC, NEO HOOKE\n" +
             DataLines({m.neo_hookean.shear_modulus_pa / 2, 2 / m.neo_hookean.bulk_modulus_pa});
    case MaterialSpec::Kind::kMooneyRivlin:
      return "*HYPERELASTIC, MOONEY-RIVLIN\n" +
             DataLines({m.mooney_rivlin.c10_pa, m.mooney_rivlin.c01_pa,
                        2 / m.mooney_rivlin.bulk_modulus_pa});
    case MaterialSpec::Kind::kPolynomial: {
      int order = 1;
      double c[4][4] = {};
      for (const PolynomialTermSpec& t : m.polynomial.terms) {
        c[t.i][t.j] = t.c_pa;
        order = std::max(order, t.i + t.j);
      }
      std::vector<double> values;
      for (int n = 1; n <= order; ++n) {
        for (int j = 0; j <= n; ++j) values.push_back(c[n - j][j]);  // C_n0, C_(n-1)1, ...
      }
      for (int k = 0; k < order; ++k) {
        values.push_back(
            k < static_cast<int>(m.polynomial.d_per_pa.size()) ? m.polynomial.d_per_pa[k] : 0.0);
      }
      return "*HYPERELASTIC, POLYNOMIAL, N=" + std::to_string(order) + "\n" + DataLines(values);
    }
    case MaterialSpec::Kind::kOgden: {
      std::vector<double> values;
      for (const OgdenTermSpec& t : m.ogden.terms) {
        values.push_back(t.mu_pa);
        values.push_back(t.alpha);
      }
      values.push_back(2 / m.ogden.bulk_modulus_pa);
      for (std::size_t k = 1; k < m.ogden.terms.size(); ++k) values.push_back(0);  // D2, D3
      return "*HYPERELASTIC, OGDEN, N=" + std::to_string(m.ogden.terms.size()) + "\n" +
             DataLines(values);
    }
    case MaterialSpec::Kind::kNone:
      break;
  }
  return "";
}

}  // namespace

Status WriteAbaqusDeck(const Problem& problem, const std::filesystem::path& file) {
  const Model& model = problem.model;
  const Mesh& mesh = model.mesh;
  std::ofstream out(file, std::ios::trunc);
  if (!out) return Status::Io("cannot write " + file.string());
  out << "** PBA " << SolverVersion() << " model of scene '" << problem.name << "'\n"
      << "** Units: m, N, Pa. Node and element numbers are PBA's indices + 1.\n"
      << "*HEADING\n"
      << (problem.name.empty() ? "pba model" : problem.name) << "\n*NODE, NSET=NALL\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    out << i + 1 << ", " << AbaqusNumber(mesh.nodes(i, 0)) << ", " << AbaqusNumber(mesh.nodes(i, 1))
        << ", " << AbaqusNumber(mesh.nodes(i, 2)) << "\n";
  }
  if (problem.element == ElementType::kTet10Md) {
    out << "** PBA solves this scene with TET10_MD (10-node, mean dilatation); CalculiX has no\n"
           "** mean-dilatation 10-node element, so C3D10 here is the plain element, which locks\n"
           "** when nearly incompressible: set mesh.element: TET10 to compare the same discrete\n"
           "** problem.\n";
  } else if (mesh.shape() == ElementShape::kTet10) {
    out << "** PBA solves this scene with TET10; C3D10 is the same element (the same 10 nodes in\n"
           "** the same order, the same 4-point rule), so both codes answer one discrete "
           "problem.\n";
  } else if (problem.element == ElementType::kHex8) {
    out << "** PBA solves this scene with HEX8 (mean dilatation); C3D8 is fully integrated and\n"
           "** locks when nearly incompressible: set mesh.element: HEX8_FULL to compare the same\n"
           "** discrete problem.\n";
  } else if (problem.analysis == AnalysisSpec::Type::kNonlinearStatic &&
             problem.element == ElementType::kTet4Anp) {
    out << "** PBA solves this scene with TET4_ANP (average nodal pressure); C3D4 is the plain\n"
           "** tetrahedron, which locks when nearly incompressible: set mesh.element: TET4 (or\n"
           "** TET10, C3D10) to compare the same discrete problem.\n";
  }
  // PBA's 10-node order (corners, then edges (0,1) (1,2) (2,0) (0,3) (1,3)
  // (2,3)) is C3D10's, so the nodes go out as they are.
  out << "*ELEMENT, TYPE=" << KindOf(problem.element).abaqus_type << ", ELSET=EALL\n";
  for (int e = 0; e < mesh.num_elements(); ++e) {
    out << e + 1;
    for (int node : mesh.ElementNodes(e)) out << ", " << node + 1;
    out << "\n";
  }
  for (const auto& [name, set] : mesh.face_sets) {
    out << "*NSET, NSET=" << Upper(name) << "\n";
    WriteIdList(out, set.nodes);
  }
  // One element set, material and section per material of the model (the
  // scene's, a region's, an inclusion's, a library entry's); an orthotropic
  // model's axes as a rectangular system: local 1 through point a, the 1-2
  // plane through point b (the orthonormalised axes, so the deck's
  // Gram-Schmidt is PBA's).
  const SceneMaterials& materials = model.materials;
  std::vector<std::vector<int>> elements_of(materials.specs.size());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    elements_of[materials.of_element[e]].push_back(e);
  }
  for (std::size_t k = 0; k < materials.specs.size(); ++k) {
    if (elements_of[k].empty()) continue;
    const MaterialSpec& spec = materials.specs[k];
    const std::string name = "TISSUE" + (k == 0 ? std::string() : "_" + std::to_string(k));
    out << "** " << materials.labels[k] << "\n*ELSET, ELSET=" << name << "\n";
    WriteIdList(out, elements_of[k]);
    const bool oriented = spec.kind == MaterialSpec::Kind::kOrthotropicElastic;
    if (oriented) {
      const OrthotropicElasticParams& p = spec.orthotropic_elastic;
      const Eigen::Matrix3d q = MaterialFrame(p.axis_1, p.axis_2);
      out << "*ORIENTATION, NAME=AXES_" << name << ", SYSTEM=RECTANGULAR\n"
          << DataLines({q(0, 0), q(1, 0), q(2, 0), q(0, 1), q(1, 1), q(2, 1)});
    }
    out << "*MATERIAL, NAME=" << name << "\n"
        << MaterialCards(spec) << "*SOLID SECTION, ELSET=" << name << ", MATERIAL=" << name
        << (oriented ? ", ORIENTATION=AXES_" + name : std::string()) << "\n";
  }
  if (problem.analysis == AnalysisSpec::Type::kNonlinearStatic) {
    // Geometric nonlinearity, automatic incrementation from the same first
    // increment PBA takes.
    const int increments = problem.nonlinear.increments;
    const std::string first_and_largest = AbaqusNumber(1.0 / increments) + ", 1.0, 1e-5, " +
                                          AbaqusNumber(std::max(0.5, 1.0 / increments)) + "\n";
    // Field convergence controls as tight as PBA's own (relative residual
    // and correction 1e-8 instead of 5e-3 and 1e-2), so both codes answer
    // the same discrete problem to the same precision.
    out << "*STEP, NLGEOM, INC=10000\n*STATIC\n"
        << first_and_largest << "*CONTROLS, PARAMETERS=FIELD\n1e-8, 1e-8\n*BOUNDARY\n";
  } else {
    out << "*STEP\n*STATIC\n*BOUNDARY\n";
  }
  // The resolved constraints, one per unknown: the deck needs no rule for
  // conditions that overlap on shared edges.
  for (int dof = 0; dof < model.dofs.num_dofs(); ++dof) {
    if (!model.dofs.prescribed(dof)) continue;
    out << dof / 3 + 1 << ", " << dof % 3 + 1 << ", " << dof % 3 + 1 << ", "
        << AbaqusNumber(model.dofs.prescribed_value(dof)) << "\n";
  }
  // Pressure on element faces (C3D4 and C3D10 faces alike, by their corners:
  // S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1, i.e. the face opposite
  // corner 4, 3, 1, 2; a C3D10 face also holds the mid-edge nodes of its
  // edges); with NLGEOM CalculiX makes it a follower load, as PBA does.
  static const int kFaceOpposite[4] = {3, 4, 2, 1};  // corner (0-based) -> face label
  bool dload = false;
  for (const SurfaceLoad& bc : problem.surface_loads) {
    if (bc.kind != SurfaceLoad::Kind::kPressure || bc.pressure_pa == 0) continue;
    if (!dload) out << "*DLOAD\n";
    dload = true;
    const FaceSet& set = mesh.face_sets.at(bc.set);
    if (ShapeInfo(mesh.shape()).boundary_face == BoundaryFace::kQuad4) {
      // C3D8 faces S1..S6 (mesh.h, kHex8Faces).
      for (const auto& [element, face] : QuadFaceElements(mesh, set)) {
        if (element < 0) continue;
        out << element + 1 << ", P" << face + 1 << ", " << AbaqusNumber(bc.pressure_pa) << "\n";
      }
      continue;
    }
    for (const auto& [element, corner] : FaceElements(mesh, set)) {
      if (element < 0) continue;
      out << element + 1 << ", P" << kFaceOpposite[corner] << ", " << AbaqusNumber(bc.pressure_pa)
          << "\n";
    }
  }
  // Tractions and gravity as the nodal forces PBA turns them into (exact for
  // uniform loads; on a 10-node mesh the consistent forces, mid-edge nodes
  // included).
  const ExternalLoads loads = BuildLoads(problem);
  bool cload = false;
  for (int dof = 0; dof < model.dofs.num_dofs(); ++dof) {
    const double f = loads.dead_force()(dof);
    if (f == 0) continue;
    if (!cload) out << "*CLOAD\n";
    cload = true;
    out << dof / 3 + 1 << ", " << dof % 3 + 1 << ", " << AbaqusNumber(f) << "\n";
  }
  for (const auto& name : problem.outputs.reaction_sets) {
    out << "*NODE PRINT, NSET=" << Upper(name) << ", TOTALS=ONLY\nRF\n";
  }
  out << "*NODE PRINT, NSET=NALL\nU\n*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n";
  out.close();
  if (!out) return Status::Io("cannot write " + file.string());
  return Status::Ok();
}

}  // namespace pba
