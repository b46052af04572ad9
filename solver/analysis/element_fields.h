// The per-element fields of a Solution (strain, stress, von Mises; with
// finite strain also the Almansi strain, the second Piola-Kirchhoff stress
// and J), written in one place from each element's samples: the static
// analyses' integration points, the explicit engine's one point.
//
// Voigt order xx yy zz yz xz xy, engineering shear in the strains; stresses
// [Pa]. The configuration of each quantity: Green-Lagrange strain and PK2
// on the reference, Almansi strain and Cauchy stress on the current one.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>

#include "core/thread_context.h"
#include "material/hyperelastic.h"
#include "material/voigt.h"
#include "pba/solve.h"

namespace pba {

// The finite-strain fields at a material point, or an element's means.
struct ElementFields {
  Vector6d green = Vector6d::Zero();    // Green-Lagrange strain E = (C - I) / 2
  Vector6d almansi = Vector6d::Zero();  // Euler-Almansi e = (I - (F F^T)^-1) / 2
  Vector6d pk2 = Vector6d::Zero();      // second Piola-Kirchhoff stress S
  Vector6d cauchy = Vector6d::Zero();   // Cauchy stress sigma = F S F^T / J
  double j = 0;                         // J = det F (or the element's volume ratio)
};

// The fields of deformation gradient `f` under second Piola-Kirchhoff
// stress `pk2` (sigma = F S F^T / J), J = det F.
ElementFields FieldsFromPk2(const Eigen::Matrix3d& f, const Vector6d& pk2);
// The same under Cauchy stress `cauchy` (S = J F^-1 sigma F^-T).
ElementFields FieldsFromCauchy(const Eigen::Matrix3d& f, const Vector6d& cauchy);

// The fields of deformation gradient `f` under `material`'s stress; with a
// `pressure` (average nodal pressure: the element's mean of its corners'
// U'(J_a)), the isochoric stress plus that pressure's p J C^-1, and J
// reported as `volume_ratio` (the corners' mean volume ratio, which the
// element's energy is written in).
ElementFields FieldsAt(const HyperelasticMaterial& material, const Eigen::Matrix3d& f,
                       std::optional<double> pressure = std::nullopt, double volume_ratio = 0);

// An element's volume-weighted means: Add each integration point with its
// share of the element's volume, then Mean() divides every sum by the total
// weight.
class ElementFieldSum {
 public:
  void Add(double weight, const ElementFields& point);
  ElementFields Mean() const;
  double weight() const { return weight_; }
  // The largest Green-Lagrange component (magnitude) at the points added;
  // with one point, that of the mean (the same up to rounding, and the
  // number written).
  double LargestStrain() const;

 private:
  ElementFields sum_;
  double weight_ = 0, largest_ = 0;
  int points_ = 0;
};

// Sizes the small-strain fields (strain, stress_pa, von_mises_pa) for
// `elements` elements, zero.
void StartSmallStrainFields(int elements, Solution* solution);
// Sizes them and the finite-strain ones (almansi_strain, pk2_stress_pa
// zero, jacobian one): an element never written reads undeformed.
void StartFiniteStrainFields(int elements, Solution* solution);

// Element e's strain, stress and the von Mises stress of `stress`.
void WriteSmallStrainFields(int e, const Vector6d& strain, const Vector6d& stress,
                            Solution* solution);
// Element e's finite-strain fields (strain the Green-Lagrange, stress_pa the
// Cauchy); returns the largest Green-Lagrange component (magnitude).
double WriteFiniteStrainFields(int e, const ElementFields& fields, Solution* solution);

// Writes every element's finite-strain fields (StartFiniteStrainFields,
// then the means of the samples `sample(e, &sum)` adds for element e) on
// `threads`, element by element; returns the largest Green-Lagrange
// component. The body side of field recovery (DiscreteBody::RecoverFields).
double RecoverFiniteStrainFields(int elements, const ThreadContext& threads, Solution* solution,
                                 const std::function<void(int e, ElementFieldSum* sum)>& sample);

}  // namespace pba
