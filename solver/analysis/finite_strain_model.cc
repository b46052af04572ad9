#include "analysis/finite_strain_model.h"

#include <cstdio>
#include <cstdlib>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/element_fields.h"
#include "analysis/hex8_model.h"
#include "analysis/tet10_model.h"
#include "fem/tet4_finite_strain.h"
#include "material/hyperelastic.h"
#include "material/material_field.h"

namespace pba {
namespace {

class Tet4Model final : public FiniteStrainModel {
 public:
  Tet4Model(const Mesh& mesh, const MaterialField& field, const ThreadContext& threads,
            std::unique_ptr<MaterialField> owned = nullptr)
      : mesh_(mesh),
        owned_(std::move(owned)),
        field_(owned_ ? *owned_ : field),
        threads_(threads),
        colours_(ColourElements(mesh)) {
    geometry_.reserve(mesh.num_elements());
    for (int e = 0; e < mesh.num_elements(); ++e) {
      geometry_.push_back(ComputeTet4Geometry(TetCorners(mesh, e)));
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

  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    const ElementKernel kernel = [&](int e, Matrix12d* k, Vector12d* f) {
      Tet4FiniteStrainResult r;
      if (!Tet4FiniteStrain(geometry_[e], GatherElement(mesh_, e, u), field_.At(e), true, &r)) {
        return false;
      }
      *k = r.tangent;
      *f = -r.force;
      return true;
    };
    AssemblyOptions threaded = options;
    threaded.threads = threads_;
    return AssembleSystem(
        mesh_, dofs, colours_, kernel, threaded, [](double) { return true; }, system);
  }

  std::string Describe() const override { return "TET4, total Lagrangian"; }

  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override {
    return RecoverFiniteStrainFields(
        mesh_.num_elements(), threads_, solution, [&](int e, ElementFieldSum* sum) {
          const Tet4Geometry& g = geometry_[e];
          sum->Add(g.volume,
                   FieldsAt(field_.At(e), DeformationGradient(g, GatherElement(mesh_, e, u))));
        });
  }

 private:
  // The force of every element, or with `own` (may be null) of those that
  // touch its nodes.
  bool Forces(const Eigen::VectorXd& u, const std::vector<char>* own, Eigen::VectorXd* force,
              double* energy) const {
    *force = Eigen::VectorXd::Zero(u.size());
    bool ok = true;
    double total = 0;
    for (const auto& colour : colours_) {
      // A colour too small to repay starting a team runs on one thread (a
      // Newton solve on a small mesh evaluates the force thousands of times).
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) \
    reduction(&& : ok) reduction(+ : total) if (threads_.Parallel(colour.size()))
      for (std::size_t k = 0; k < colour.size(); ++k) {
        const int e = colour[k];
        if (own != nullptr && !TouchesAny(mesh_.tets[e], *own)) continue;
        Tet4FiniteStrainResult r;
        if (!Tet4FiniteStrain(geometry_[e], GatherElement(mesh_, e, u), field_.At(e), false, &r)) {
          ok = false;
          continue;
        }
        total += r.energy;
        for (int a = 0; a < 4; ++a) {
          force->segment<3>(3 * mesh_.tets[e][a]) += r.force.segment<3>(3 * a);
        }
      }
    }
    if (energy) *energy = total;
    return ok && force->allFinite() && std::isfinite(total);
  }

  const Mesh& mesh_;
  std::unique_ptr<MaterialField> owned_;  // a uniform field made for one material
  const MaterialField& field_;
  const ThreadContext threads_;
  std::vector<std::vector<int>> colours_;
  std::vector<Tet4Geometry> geometry_;
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeFiniteStrainModel(ElementType element, const Mesh& mesh,
                                                         const MaterialField& field,
                                                         const ThreadContext& threads) {
  switch (element) {
    case ElementType::kTet4:
      return MakeTet4Model(mesh, field, threads);
    case ElementType::kTet4Anp:
      return MakeAverageNodalPressureTet4Model(mesh, field, threads);
    case ElementType::kTet10:
      return MakeTet10Model(mesh, field, threads);
    case ElementType::kTet10Md:
      return MakeTet10MdModel(mesh, field, threads);
    case ElementType::kHex8:
      return MakeHex8Model(mesh, field, threads);
    case ElementType::kHex8Full:
      return MakeHex8FullModel(mesh, field, threads);
    case ElementType::kDefault:
      break;
  }
  std::fprintf(stderr, "pba: MakeFiniteStrainModel needs a resolved element type\n");
  std::abort();
}

bool FiniteStrainModel::InternalForceShare(const Eigen::VectorXd& u, const std::vector<char>& own,
                                           Eigen::VectorXd* force) const {
  const bool ok = InternalForce(u, force, nullptr);
  KeepRowsOf(own, force);
  return ok;
}

void KeepRowsOf(const std::vector<char>& own, Eigen::VectorXd* force) {
  for (std::size_t n = 0; n < own.size(); ++n) {
    if (!own[n]) force->segment<3>(3 * static_cast<Eigen::Index>(n)).setZero();
  }
}

BodyForce FiniteStrainModel::Force(const Eigen::VectorXd& u, const Eigen::VectorXd* v,
                                   Eigen::VectorXd* f_int) {
  BodyForce out;
  out.ok = InternalForce(u, f_int, &out.energy);
  return out;
}

void FiniteStrainModel::KeepHistoryIn(MaterialField* field, const Mesh* mesh,
                                      const ThreadContext& threads) {
  history_ = field;
  history_mesh_ = mesh;
  history_threads_ = threads;
}

void FiniteStrainModel::CommitHistory(const Eigen::VectorXd& u) {
  if (history_ == nullptr || !history_->viscous()) return;
  history_->Commit(ElementDeformationGradients(*history_mesh_, u, history_threads_));
}

std::vector<double> FiniteStrainModel::SaveHistory() const {
  return history_ == nullptr ? std::vector<double>() : history_->SaveHistory();
}

Status FiniteStrainModel::RestoreHistory(const std::vector<double>& values) {
  if (history_ == nullptr) return DiscreteBody::RestoreHistory(values);
  return history_->RestoreHistory(values);
}

std::unique_ptr<FiniteStrainModel> MakeTet4Model(const Mesh& mesh,
                                                 const HyperelasticMaterial& material) {
  auto field = MaterialField::Uniform(material, mesh.num_elements());
  const MaterialField& view = *field;
  return std::make_unique<Tet4Model>(mesh, view, ThreadContext(), std::move(field));
}

std::unique_ptr<FiniteStrainModel> MakeTet4Model(const Mesh& mesh, const MaterialField& field,
                                                 const ThreadContext& threads) {
  return std::make_unique<Tet4Model>(mesh, field, threads);
}

std::vector<Eigen::Matrix3d> ElementDeformationGradients(const Mesh& mesh, const Eigen::VectorXd& u,
                                                         const ThreadContext& threads) {
  std::vector<Eigen::Matrix3d> f(mesh.num_elements());
#pragma omp parallel for schedule(static) \
    num_threads(threads.threads()) if (threads.Parallel(mesh.num_elements()))
  for (int e = 0; e < mesh.num_elements(); ++e) {
    f[e] = DeformationGradient(ComputeTet4Geometry(TetCorners(mesh, e)), GatherElement(mesh, e, u));
  }
  return f;
}

}  // namespace pba
