// The element side of explicit total-Lagrangian dynamics (TLED; Miller,
// Joldes, Lance and Wittek, Commun. Numer. Meth. Engng 23:121, 2007): every
// reference quantity an element needs is computed once, before the time
// loop, and each step evaluates only
//
//   F_e = I + sum_a u_a (x) dN_a/dX,   f_a = V0_e P(F_e) dN_a/dX
//
// with P the first Piola-Kirchhoff stress. Elements:
//   - 4-node tetrahedra, plain (TET4, one F per element) or with average
//     nodal pressure (TET4_ANP; Bonet and Burton, Commun. Numer. Meth. Engng
//     14:437, 1998; Joldes, Wittek and Miller, Commun. Numer. Meth. Engng
//     25:827, 2009): the volume ratio is averaged over each node's elements
//     of one material, J_n = sum V0_e J_e / sum V0_e, the pressure U'(J_n)
//     taken at the node and each element's the mean of its four corners'.
//     This is the derivative of sum_n V_n U(J_n), so the element stays
//     conservative and does not lock when nearly incompressible;
//   - 8-node hexahedra with one point (the uniform-strain gradients of
//     Flanagan and Belytschko, IJNME 17:679, 1981, the element's mean of
//     dN_a/dX) and a stiffness hourglass control on the four modes the
//     point cannot see: q_ai = sum_b gamma_b,alpha u_bi with the
//     Flanagan-Belytschko vectors gamma = (h - (h . X) b) / 8, orthogonal to
//     every linear field (rigid motions included), and forces
//     f_a = k gamma_a q, k = kappa (K + 4 mu / 3) V0 (b : b) [N/m]; its
//     energy k |q|^2 / 2 is reported as the hourglass energy.
//
// Stress: the uncoupled split S = S_iso(F) + p J C^-1, so P = F S_iso +
// p cof F with p = U'(J) (the nodal average for TET4_ANP) less the bulk
// viscosity q, through the material-point kernel the implicit analyses
// share (material/material_point.h): neo-Hookean tissue in closed form,
// other models through HyperelasticMaterial::Isochoric. A relaxing material
// keeps, per element, its Prony state (material/viscoelastic.h), advanced
// by ViscousStep::Relax at every evaluation.
//
// Bulk viscosity (von Neumann and Richtmyer, with the linear term of
// Wilkins; as LS-DYNA's): while an element compresses, tr D = dJ/dt / J < 0,
//   q = rho l (c2 l (tr D)^2 - c1 c tr D),
// l its characteristic length and c its dilatational wave speed; it is
// subtracted from p.
//
// Data are laid out per element in flat arrays (node indices, reference
// gradients, volume, material), written element by element into a force
// buffer of the element's own, then gathered per node through a
// node-to-corner list: no two threads ever write the same number, and the
// sum is in the same order on any number of threads. One evaluation is one
// parallel region of at most three passes over the elements: V0 J for the
// nodal averages (TET4_ANP only); F, stress and forces in one (F is stored
// for the accessors, not read back), neo-Hookean elements eight at a time;
// and the gather per node (docs/performance.md, "Explicit dynamics").
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "assembly/discrete_body.h"
#include "core/thread_context.h"
#include "material/hyperelastic.h"
#include "material/viscoelastic.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

// One material of the explicit model.
struct TledMaterial {
  std::shared_ptr<const HyperelasticMaterial> model;
  PronySeries relaxation;  // no terms: elastic
  double density = 0;      // [kg/m^3], > 0
  // Neo-Hookean without relaxation: the closed-form stress.
  bool neo_hookean = false;
  double mu = 0, bulk = 0;  // initial moduli [Pa]
  std::string name;
  // Dilatational wave speed sqrt((K + 4 mu / 3) / rho) [m/s].
  double WaveSpeed() const;
};

struct TledOptions {
  bool average_nodal_pressure = true;  // tetrahedra: TET4_ANP (else TET4)
  double bulk_viscosity_linear = 0.06;
  double bulk_viscosity_quadratic = 1.5;
  double hourglass = 0.05;  // hexahedra: kappa
  // Every pass runs on this many threads, without a serial cut-off: the
  // sums are in the same order on any number (see above).
  ThreadContext threads;
};

// What one force evaluation produced beyond the forces.
struct TledEvaluation {
  double hourglass_energy = 0;  // [J]
  // First element whose F is not admissible (det F <= 0 or not finite);
  // -1 when none.
  int inverted_element = -1;
};

// The explicit engine's body (a DiscreteBody with a lumped mass and no
// tangent, whose history advances with every evaluation).
class TledModel final : public DiscreteBody {
 public:
  // `mesh` (4-node tetrahedra or 8-node hexahedra) must outlive the model;
  // material_of[e] indexes `materials`. Fails naming the element when one
  // has no positive volume, and on a material with no density.
  static Status Build(const Mesh& mesh, std::vector<TledMaterial> materials,
                      std::vector<int> material_of, const TledOptions& options,
                      std::unique_ptr<TledModel>* out);

  int num_elements() const { return num_elements_; }
  int num_nodes() const { return num_nodes_; }
  int nodes_per_element() const { return npe_; }
  const int* element_nodes(int e) const { return &conn_[npe_ * static_cast<std::size_t>(e)]; }
  double reference_volume(int e) const { return volume_[e]; }
  int material_of(int e) const { return material_of_[e]; }
  const TledMaterial& material(int e) const { return materials_[material_of_[e]]; }
  // Lumped mass per node (rho V0 shared equally among the corners) [kg].
  const Eigen::VectorXd& lumped_mass() const { return mass_; }
  // Replaces it (dynamic relaxation's fictitious masses).
  void SetLumpedMass(Eigen::VectorXd mass) { mass_ = std::move(mass); }
  // The threads its passes run on (TledOptions::threads), e.g. for a
  // benchmark that measures one model on several counts.
  void SetThreads(const ThreadContext& threads) { options_.threads = threads; }
  // Reference characteristic length of element e [m].
  double characteristic_length(int e) const { return length_[e]; }

  // The smallest stable time step l_e / c_e over the elements, at the
  // current displacement `u` (the reference one when null) and, when
  // given, velocity `v` (the bulk viscosity shortens it:
  // dt = l / (Q + sqrt(Q^2 + c^2)), Q = c1 c + c2 l |tr D| while
  // compressing). The characteristic length is the smallest altitude 3V /
  // A_max of a tetrahedron and V / A_max of a hexahedron. Sets *element to
  // the element that controls it and *length to its length [m].
  double StableTimeStep(const Eigen::VectorXd* u, const Eigen::VectorXd* v, int* element,
                        double* length) const;

  // Selective mass scaling: every element whose stable step l / c is below
  // `min_stable_step` [s] takes the density that makes it that step, its
  // added mass shared among its corners; StableTimeStep then sees the
  // scaled wave speeds (the bulk viscosity keeps the true density).
  struct MassScaling {
    int elements = 0;
    double added_mass = 0;     // [kg]
    double model_mass = 0;     // before [kg]
    double added_kinetic = 0;  // RescaleMass: the change of kinetic energy (<= 0) [J]
  };
  MassScaling ScaleMass(double min_stable_step);
  // The same during a run, at displacement u and velocity *v: elements
  // crushed below the step (their current length shrinks, and the bulk
  // viscosity shortens it further) take mass instead of shrinking the step
  // of the whole run, as LS-DYNA's DT2MS does. Their nodes keep their
  // momentum (*v is scaled down), so kinetic energy is lost, never made.
  // *stable_step, *element and *length are then what StableTimeStep(&u, v)
  // would return.
  MassScaling RescaleMass(const Eigen::VectorXd& u, Eigen::VectorXd* v, double min_stable_step,
                          double* stable_step, int* element, double* length);

  // Sets the step length used by the relaxation's internal variables;
  // call before the first evaluation and whenever the step changes.
  void SetTimeStep(double dt);

  // Internal force f_int(u, v) [N] (full length, 3 per node) at
  // displacement `u` [m] and velocity `v` [m/s] (the bulk viscosity's
  // rate). Advances the relaxation's internal variables by one step: call
  // once per time step. Elements marked eroded are skipped.
  TledEvaluation InternalForce(const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                               Eigen::VectorXd* f_int);

  // DiscreteBody: "TET4_ANP, explicit total Lagrangian" and the like;
  // Force is InternalForce (at rest when v is null) with StoredEnergy; the
  // history is the relaxing elements' Prony states, in element order.
  std::string Describe() const override;
  BodyForce Force(const Eigen::VectorXd& u, const Eigen::VectorXd* v,
                  Eigen::VectorXd* f_int) override;
  bool advances_on_evaluation() const override { return true; }
  // The fields of the last InternalForce, which must have had
  // RecordStress(true) (eroded elements read undeformed).
  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override;
  Eigen::VectorXd LumpedMass() const override { return mass_; }
  std::vector<double> SaveHistory() const override { return history_; }
  Status RestoreHistory(const std::vector<double>& values) override;

  // Per element, from the last InternalForce: F (9, row-major), the
  // pressure -tr(sigma)/3 without the bulk viscosity [Pa], and the Cauchy
  // stress (Voigt xx yy zz yz xz xy) when RecordStress(true) was set.
  const double* deformation_gradient(int e) const { return &f_[9 * static_cast<std::size_t>(e)]; }
  Eigen::Matrix3d DeformationGradient(int e) const;
  double pressure(int e) const { return pressure_[e]; }
  void RecordStress(bool on) { record_stress_ = on; }
  Vector6d CauchyStress(int e) const;

  // Erosion: removes element e from the force evaluation. With average
  // nodal pressure its V0 J stays in its corners' nodal averages, frozen
  // at its value when it went: removing it outright would move their J_n
  // at once, and with a bulk modulus a million times the shear modulus
  // that jump stores far more energy than the impact brought in. The
  // nodes thus keep the element's last volume as a filler of fixed size.
  void Erode(int e);
  // The strain energy stored at the last evaluation's deformation [J]:
  // sum_e V0 W_iso(F_e) over the elements not eroded, plus the volumetric
  // energy, sum_n V_n U(J_n) over the nodal groups with average nodal
  // pressure (eroded elements' frozen V0 J included), else sum_e V0 U(J_e).
  // Erosion is accounted for by the drop of this total. The isochoric part
  // is the elastic one (a relaxing material's viscous history is not
  // counted).
  double StoredEnergy() const;
  bool eroded(int e) const { return !eroded_.empty() && eroded_[e]; }
  // Nodes none of whose elements remain (after erosion).
  std::vector<int> OrphanNodes() const;

  // Elements of node n: corner slots c of the per-element arrays (element
  // c / npe, local node c % npe), CSR.
  const std::vector<int>& node_offsets() const { return node_start_; }
  const std::vector<int>& node_corners() const { return node_corner_; }

 private:
  TledModel() = default;
  // Element e's stable step at (u, v) (reference when null); *length its
  // characteristic length.
  double ElementStableStep(int e, const Eigen::VectorXd* u, const Eigen::VectorXd* v,
                           double* length) const;
  // The passes of InternalForce, each an `omp for` inside its one parallel
  // region: V0 J per element (TET4_ANP), the nodal pressures, the element
  // forces, the gather.
  void VolumeRatios(const Eigen::VectorXd& u);
  void AverageNodalPressure();
  // kNpe: nodes per element (4 or 8), so that the corner loops unroll.
  template <int kNpe>
  void ElementForces(const Eigen::VectorXd& u, const Eigen::VectorXd& v, TledEvaluation* eval);
  // One element of any material, and kBlock neo-Hookean ones with the same
  // arithmetic in the same order (false, having stored at most F and J, when
  // the block holds another kind of element); tled_model_test runs both.
  template <int kNpe>
  void ElementForce(int e, const double* ud, const double* vd, double* hourglass, int* inverted);
  static constexpr int kBlock = 8;
  template <int kNpe>
  bool NeoHookeanBlock(int e0, const double* ud, const double* vd, double* hourglass);
  void HourglassForces(int e, const double* ud, double* force, double* hourglass) const;
  void Gather(Eigen::VectorXd* f_int) const;
  // group_volume_[g] from the elements not eroded.
  void SumGroupVolume(int g);

  const Mesh* mesh_ = nullptr;
  int num_elements_ = 0, num_nodes_ = 0, npe_ = 4;
  TledOptions options_;
  std::vector<TledMaterial> materials_;
  std::vector<double> wave_speed_;  // per material, TledMaterial::WaveSpeed() [m/s]
  std::vector<int> material_of_;
  std::vector<int> conn_;            // npe per element
  std::vector<double> grad_;         // 3 npe per element: dN_a/dX_j at a * 3 + j [1/m]
  std::vector<double> volume_;       // V0 [m^3]
  std::vector<double> length_;       // reference characteristic length [m]
  std::vector<double> gamma_;        // hexahedra: 32 per element, gamma_{a alpha} at a * 4 + alpha
  std::vector<double> hourglass_k_;  // hexahedra [N/m]
  Eigen::VectorXd mass_;
  std::vector<double> speed_scale_;  // per element c' / c after mass scaling (empty: 1)
  std::vector<int> node_start_, node_corner_;
  // Average nodal pressure: the group (node, material) of each corner, and
  // each group's elements (CSR) with the sum of their V0 (the elements not
  // eroded).
  bool anp_ = false;
  std::vector<int> corner_group_;
  std::vector<int> group_start_, group_element_;
  std::vector<double> group_volume_;  // sum V0 [m^3]
  std::vector<int> group_material_;
  std::vector<double> group_pressure_;
  std::vector<double> volume_ratio_;  // V0 J per element, from the first pass [m^3]
  // Per element, from the last evaluation.
  std::vector<double> f_;         // 9 per element
  std::vector<double> j_;         // det F
  std::vector<double> pressure_;  // -tr(sigma)/3 without q [Pa]
  std::vector<double> stress_;    // 6 per element when record_stress_
  bool record_stress_ = false;
  std::vector<double> force_;  // 3 npe per element
  std::vector<char> eroded_;
  // Relaxation: per element the committed S_iso (6) and H_k (6 per term),
  // and per material the step's factors.
  double dt_ = 0;
  std::vector<ViscousStep> steps_;
  std::vector<int> history_start_;  // per element, offset into history_ (-1: elastic)
  std::vector<double> history_;
};

}  // namespace pba
