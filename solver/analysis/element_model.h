// A FiniteStrainModel for meshes of one kind of element whose kernel
// computes force, energy and tangent element by element (10-node tetrahedra,
// hexahedra): the force is scattered colour by colour (elements of a colour
// share no node), the tangent assembled by the colour-parallel assembler,
// and an inverted element reported by its lowest index, the same on any
// number of threads. Internal to the analyses; the element supplies:
//
//   static constexpr int kNodes;   using Geometry, Result, Unknowns, Kernel;
//   static bool Fits(const Mesh&); static const char* Requirement();
//   static Geometry ComputeGeometry(const Mesh&, int e);
//   static std::array<int, kNodes> Nodes(const Mesh&, int e);
//   static Unknowns Gather(const Mesh&, int e, const Eigen::VectorXd& u);
//   static Status AssembleSystem(mesh, dofs, colours, kernel, options, keep_going, system);
//   bool Evaluate(const Geometry&, const Unknowns&, const HyperelasticMaterial&,
//                 bool with_tangent, bool drop_pressure_stiffness, Result*) const;
//   std::string Describe() const;
//   // Whether Result carries a volume constraint per element (mean
//   // dilatation: volume_gradient, volumetric_weight) for a
//   // VolumetricSplit.
//   bool SplitsVolume() const;
//   // Field recovery: kPoints integration points; the element's mean
//   // volume ratio (mean dilatation; any number otherwise) and the F its
//   // stress is evaluated with at point q.
//   static constexpr int kPoints;
//   double Dilatation(const Geometry&, const Unknowns&) const;
//   Eigen::Matrix3d PointF(const Geometry&, const Unknowns&, int q, double theta) const;
//
// Geometry has `grad` (dN/dX per integration point), `volume` (each
// point's share of the element's volume) and `min_jacobian`.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "analysis/element_fields.h"
#include "analysis/finite_strain_model.h"
#include "material/hyperelastic.h"
#include "material/material_field.h"

namespace pba {

template <typename Element>
class ElementModel final : public FiniteStrainModel {
 public:
  // `field` gives each element's material (only its base: these elements
  // keep no history, see MaterialField); `owned` is a field made for the
  // model, else `field` must outlive it. The passes run on `threads`, and
  // on the calling thread below kMinParallelWork elements.
  ElementModel(const Mesh& mesh, const MaterialField& field, Element element,
               const ThreadContext& threads, std::unique_ptr<MaterialField> owned = nullptr)
      : mesh_(mesh),
        owned_(std::move(owned)),
        field_(owned_ ? *owned_ : field),
        element_(element),
        threads_(threads),
        parallel_(threads.Parallel(mesh.num_elements())),
        colours_(ColourElements(mesh)) {
    if (mesh.num_elements() > 0 && !Element::Fits(mesh)) {
      std::fprintf(stderr, "pba: %s\n", Element::Requirement());
      std::abort();
    }
    geometry_.resize(mesh.num_elements());
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int e = 0; e < mesh.num_elements(); ++e) {
      geometry_[e] = Element::ComputeGeometry(mesh, e);
    }
  }

  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    return Forces(u, nullptr, force, energy);
  }
  bool InternalForceShare(const Eigen::VectorXd& u, const std::vector<char>& own,
                          Eigen::VectorXd* force) const override {
    if (!Forces(u, &own, force, nullptr)) return false;
    KeepRowsOf(own, force);
    return true;
  }

  // The force of every element, or with `own` (may be null) of those that
  // touch its nodes.
  bool Forces(const Eigen::VectorXd& u, const std::vector<char>* own, Eigen::VectorXd* force,
              double* energy) const {
    *force = Eigen::VectorXd::Zero(u.size());
    bool ok = true;
    double total = 0;
    for (const auto& colour : colours_) {
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_) \
    reduction(&& : ok) reduction(+ : total)
      for (std::size_t k = 0; k < colour.size(); ++k) {
        const int e = colour[k];
        if (own != nullptr && !TouchesAny(Element::Nodes(mesh_, e), *own)) continue;
        typename Element::Result r;
        if (!element_.Evaluate(geometry_[e], Element::Gather(mesh_, e, u), field_.Base(e), false,
                               false, &r)) {
          ok = false;
          continue;
        }
        total += r.energy;
        const auto nodes = Element::Nodes(mesh_, e);
        for (int a = 0; a < Element::kNodes; ++a) {
          force->template segment<3>(3 * nodes[a]) += r.force.template segment<3>(3 * a);
        }
      }
    }
    if (energy) *energy = total;
    return ok && force->allFinite() && std::isfinite(total);
  }

  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    system->split = VolumetricSplit();
    const bool split = options.volumetric_split && element_.SplitsVolume();
    if (split && options.own_nodes != nullptr) {
      return Status::Internal("a volumetric split is not assembled partitioned between ranks");
    }
    // Each element's constraint, when asked for: dv/dx and U''(theta) / V.
    std::vector<typename Element::Unknowns> gradients(split ? mesh_.num_elements() : 0);
    std::vector<double> weights(gradients.size());
    const typename Element::Kernel kernel = [&](int e, auto* k, auto* f) {
      typename Element::Result r;
      if (!element_.Evaluate(geometry_[e], Element::Gather(mesh_, e, u), field_.Base(e), true,
                             options.drop_pressure_stiffness, &r)) {
        return false;
      }
      *k = r.tangent;
      *f = -r.force;
      if (split) {
        gradients[e] = r.volume_gradient;
        weights[e] = r.volumetric_weight;
      }
      return true;
    };
    AssemblyOptions threaded = options;
    threaded.threads = threads_;
    const Status status = Element::AssembleSystem(
        mesh_, dofs, colours_, kernel, threaded, [](double) { return true; }, system);
    if (status.ok() && split) BuildSplit(dofs, gradients, weights, &system->split);
    if (status.code() != Status::Code::kNumerical) return status;
    // The assembly stops at whichever failing element a thread met first;
    // the message names the lowest one.
    const int e = LowestInverted(u);
    if (e >= 0 && !(geometry_[e].min_jacobian > 0)) {
      return Status::Numerical("element " + std::to_string(e) +
                               " is inverted in the reference configuration (det J <= 0)");
    }
    if (e >= 0) {
      return Status::Numerical("element " + std::to_string(e) +
                               " could not be evaluated (inverted: det F <= 0)");
    }
    return status;
  }

  std::string Describe() const override { return element_.Describe(); }

  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override {
    return RecoverFiniteStrainFields(
        mesh_.num_elements(), threads_, solution, [&](int e, ElementFieldSum* sum) {
          const auto& g = geometry_[e];
          const auto ue = Element::Gather(mesh_, e, u);
          const double theta = element_.Dilatation(g, ue);
          for (int q = 0; q < Element::kPoints; ++q) {
            sum->Add(g.volume[q], FieldsAt(field_.At(e), element_.PointF(g, ue, q, theta)));
          }
        });
  }

 private:
  // The constraints on the free unknowns, one per element (VolumetricSplit).
  void BuildSplit(const DofMap& dofs, const std::vector<typename Element::Unknowns>& gradients,
                  const std::vector<double>& weights, VolumetricSplit* split) const {
    const int ne = mesh_.num_elements();
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(static_cast<std::size_t>(ne) * 3 * Element::kNodes);
    split->weight.resize(ne);
    split->volume.resize(ne);
    split->shear_modulus.resize(ne);
    for (int e = 0; e < ne; ++e) {
      const auto nodes = Element::Nodes(mesh_, e);
      for (int a = 0; a < Element::kNodes; ++a) {
        for (int i = 0; i < 3; ++i) {
          const int f = dofs.free_index(3 * nodes[a] + i);
          if (f >= 0) entries.emplace_back(e, f, gradients[e](3 * a + i));
        }
      }
      split->weight(e) = weights[e];
      double volume = 0;
      for (double v : geometry_[e].volume) volume += v;
      split->volume(e) = volume;
      split->shear_modulus(e) = field_.Base(e).ShearModulus();
    }
    split->b.resize(ne, dofs.num_free());
    split->b.setFromTriplets(entries.begin(), entries.end());
  }

  // The lowest element whose reference det J or whose F at an integration
  // point at `u` is not admissible; -1 when there is none.
  int LowestInverted(const Eigen::VectorXd& u) const {
    const int ne = mesh_.num_elements();
    int lowest = ne;
    // clang-format splits "min : lowest" across the continuation.
    // clang-format off
#pragma omp parallel for schedule(static) reduction(min : lowest) \
    num_threads(threads_.threads()) if (parallel_)
    // clang-format on
    for (int e = 0; e < ne; ++e) {
      const auto& g = geometry_[e];
      bool bad = !(g.min_jacobian > 0);
      const auto ue = Element::Gather(mesh_, e, u);
      for (std::size_t q = 0; q < g.grad.size() && !bad; ++q) {
        Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
        for (int a = 0; a < Element::kNodes; ++a) {
          f += ue.template segment<3>(3 * a) * g.grad[q].row(a);
        }
        bad = !IsAdmissible(f);
      }
      if (bad) lowest = std::min(lowest, e);
    }
    return lowest < ne ? lowest : -1;
  }

  const Mesh& mesh_;
  std::unique_ptr<MaterialField> owned_;
  const MaterialField& field_;
  const Element element_;
  const ThreadContext threads_;
  const bool parallel_;  // threads_.Parallel(elements)
  std::vector<std::vector<int>> colours_;
  std::vector<typename Element::Geometry> geometry_;
};

// An ElementModel of one material for every element (a field made for it).
template <typename Element>
std::unique_ptr<FiniteStrainModel> MakeElementModel(const Mesh& mesh,
                                                    const HyperelasticMaterial& material,
                                                    Element element) {
  auto field = MaterialField::Uniform(material, mesh.num_elements());
  const MaterialField& view = *field;
  return std::make_unique<ElementModel<Element>>(mesh, view, element, ThreadContext(),
                                                 std::move(field));
}

}  // namespace pba
