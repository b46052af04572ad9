// The element kinds a scene can name (mesh.element), in one table: each
// kind's name, nodes, integration points, volumetric treatment, and which
// analyses and histories it supports. Validation, the analysis dispatch,
// the summary and the CalculiX deck read the table instead of listing
// element types themselves; a new element is a row here plus its models.
#pragma once

#include <span>

#include "pba/scene.h"

namespace pba {

struct ElementKind {
  // How the volumetric stress is integrated.
  enum class Volumetric {
    kPointwise,       // at every integration point: locks when nearly incompressible
    kNodalAverage,    // averaged over the nodes (TET4_ANP)
    kMeanDilatation,  // constant over the element (HEX8, TET10_MD)
  };

  ElementType type;
  const char* name;        // as in mesh.element: "TET4_ANP"
  int nodes;               // per element: 4, 10 or 8
  int integration_points;  // of the implicit analyses' models
  Volumetric volumetric;
  bool linear_static;         // LINEAR_STATIC takes it
  bool finite_strain;         // NONLINEAR_STATIC and QUASI_STATIC take it
  bool explicit_engine;       // EXPLICIT_DYNAMIC and DYNAMIC_RELAXATION take it
  bool keeps_history;         // relaxation and growth in the implicit analyses
  const char* explicit_form;  // its form in the explicit engine ("" when it has none)
  const char* abaqus_type;    // the Abaqus / CalculiX element on the same nodes: "C3D4"
};

// Every kind, in the order of ElementType (kDefault excepted).
std::span<const ElementKind> ElementKinds();

// The row of `type`; kDefault must be resolved first (ResolvedElement),
// and a kDefault here is a bug: it aborts.
const ElementKind& KindOf(ElementType type);

// The element a scene gets: the one it names, else TET4 for LINEAR_STATIC
// and TET4_ANP for the other analyses.
inline ElementType ResolveElement(ElementType named, AnalysisSpec::Type analysis) {
  if (named != ElementType::kDefault) return named;
  return analysis == AnalysisSpec::Type::kLinearStatic ? ElementType::kTet4 : ElementType::kTet4Anp;
}

// Whether an element locks when nearly incompressible (a volumetric
// constraint per integration point).
inline bool Locks(const ElementKind& kind) {
  return kind.volumetric == ElementKind::Volumetric::kPointwise;
}

}  // namespace pba
