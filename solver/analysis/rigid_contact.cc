#include "analysis/rigid_contact.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

#include "core/format.h"

namespace pba {
namespace {

// Area of the bilinear quad through `x` [m^2]: |x_,xi x x_,eta| integrated
// by the 2 x 2 Gauss rule (exact for a flat parallelogram).
double QuadArea(const Eigen::Matrix<double, 4, 3>& x) {
  constexpr double kXi[4] = {-1, 1, 1, -1}, kEta[4] = {-1, -1, 1, 1};
  const double g = 1 / std::sqrt(3.0);
  double area = 0;
  for (double xi : {-g, g}) {
    for (double eta : {-g, g}) {
      Eigen::Vector3d d_xi = Eigen::Vector3d::Zero(), d_eta = Eigen::Vector3d::Zero();
      for (int a = 0; a < 4; ++a) {
        d_xi += 0.25 * kXi[a] * (1 + eta * kEta[a]) * x.row(a).transpose();
        d_eta += 0.25 * kEta[a] * (1 + xi * kXi[a]) * x.row(a).transpose();
      }
      area += d_xi.cross(d_eta).norm();  // Gauss weights 1
    }
  }
  return area;
}

class ContactModel : public FiniteStrainModel {
 public:
  ContactModel(const FiniteStrainModel& body, std::vector<const RigidContact*> contacts)
      : body_(body), contacts_(std::move(contacts)) {}

  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    if (!body_.InternalForce(u, force, energy)) return false;
    for (const RigidContact* contact : contacts_) contact->AddInternalForce(u, force, energy);
    return force->allFinite() && (energy == nullptr || std::isfinite(*energy));
  }

  // The body's share, and the contacts' forces on the same rows.
  bool InternalForceShare(const Eigen::VectorXd& u, const std::vector<char>& own,
                          Eigen::VectorXd* force) const override {
    if (!body_.InternalForceShare(u, own, force)) return false;
    Eigen::VectorXd contact = Eigen::VectorXd::Zero(u.size());
    for (const RigidContact* c : contacts_) c->AddInternalForce(u, &contact, nullptr);
    KeepRowsOf(own, &contact);
    *force += contact;
    return force->allFinite();
  }

  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    PBA_RETURN_IF_ERROR(body_.Assemble(u, dofs, options, system));
    for (const RigidContact* contact : contacts_) contact->AddTangent(u, dofs, system, options);
    return Status::Ok();
  }

  // The tissue's fields: contact adds forces, not elements.
  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override {
    return body_.RecoverFields(u, solution);
  }

  std::string Describe() const override {
    const int n = static_cast<int>(contacts_.size());
    return body_.Describe() + Format(", with %d rigid contact%s", n, n == 1 ? "" : "s");
  }

 private:
  const FiniteStrainModel& body_;
  std::vector<const RigidContact*> contacts_;
};

}  // namespace

RigidContact::RigidContact(const Mesh& mesh, const FaceSet& set, RigidBody body, double penalty,
                           double friction, double tolerance)
    : mesh_(mesh),
      body_(std::move(body)),
      penalty_(penalty),
      friction_(friction),
      tolerance_(tolerance) {
  if (body_.axis.norm() > 0) body_.axis.normalize();
  nodes_ = set.nodes;
  if (nodes_.empty()) {
    FaceSet copy = set;
    CollectFaceSetNodes(&copy);
    nodes_ = copy.nodes;
  }
  std::vector<int> index(mesh.num_nodes(), -1);
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) index[nodes_[k]] = k;
  areas_.assign(nodes_.size(), 0.0);
  const auto add = [&](int node, double area) {
    if (index[node] >= 0) areas_[index[node]] += area;
  };
  const auto point = [&](int node) { return Eigen::Vector3d(mesh.nodes.row(node).transpose()); };
  for (std::size_t t = 0; t < set.triangles.size(); ++t) {
    const auto& tri = set.triangles[t];
    const double area =
        0.5 * (point(tri[1]) - point(tri[0])).cross(point(tri[2]) - point(tri[0])).norm();
    if (t < set.triangle_midside.size()) {
      // A 6-node triangle: its four sub-triangles (corner ones and the
      // middle one) each share a third of their area A/4 among their
      // nodes, so a corner gets A/12 and a mid-edge node A/4; all nodes
      // carry area and can touch the rigid surface.
      for (int c = 0; c < 3; ++c) {
        add(tri[c], area / 12);
        add(set.triangle_midside[t][c], area / 4);
      }
    } else {
      for (int c = 0; c < 3; ++c) add(tri[c], area / 3);
    }
  }
  for (const auto& quad : set.quads) {
    Eigen::Matrix<double, 4, 3> x;
    for (int a = 0; a < 4; ++a) x.row(a) = mesh.nodes.row(quad[a]);
    const double area = QuadArea(x);
    for (int a = 0; a < 4; ++a) add(quad[a], area / 4);
  }
  lambda_.assign(nodes_.size(), 0.0);
  stick_.resize(nodes_.size());
  for (std::size_t k = 0; k < nodes_.size(); ++k) stick_[k] = point(nodes_[k]) - Centre();
}

void RigidContact::SetBody(RigidBody body) {
  body_ = std::move(body);
  if (body_.axis.norm() > 0) body_.axis.normalize();
}

RigidContact::NodeState RigidContact::Evaluate(int k, const Eigen::VectorXd& u) const {
  NodeState s;
  const int node = nodes_[k];
  const Eigen::Vector3d x = mesh_.nodes.row(node).transpose() + u.segment<3>(3 * node);
  s.relative = x - Centre();
  s.candidate = true;
  switch (body_.shape) {
    case ContactSpec::Shape::kSphere:
      s.distance = s.relative.norm();
      // A node at the very centre has no normal; push it along the axis.
      s.normal = s.distance > 0 ? Eigen::Vector3d(s.relative / s.distance) : body_.axis;
      s.gap = s.distance - body_.radius;
      break;
    case ContactSpec::Shape::kFlatPunch: {
      s.gap = s.relative.dot(body_.axis);
      s.normal = body_.axis;
      s.candidate = (s.relative - s.gap * body_.axis).norm() <= body_.radius;
      break;
    }
    default:  // kPlane
      s.gap = s.relative.dot(body_.axis);
      s.normal = body_.axis;
      break;
  }
  s.pressure = s.candidate ? std::max(0.0, lambda_[k] - penalty_ * s.gap) : 0.0;
  if (friction_ > 0 && s.pressure > 0) {
    const Eigen::Matrix3d tangential =
        Eigen::Matrix3d::Identity() - s.normal * s.normal.transpose();
    const Eigen::Vector3d trial = -penalty_ * (tangential * (s.relative - stick_[k]));
    s.trial_norm = trial.norm();
    const double limit = friction_ * s.pressure;
    s.sliding = s.trial_norm > limit;
    s.traction = s.sliding ? Eigen::Vector3d(trial * (limit / s.trial_norm)) : trial;
  }
  return s;
}

void RigidContact::AddInternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* f_int,
                                    double* energy) const {
  double sum = 0;
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const NodeState s = Evaluate(k, u);
    const double area = areas_[k];
    // dPi/dx = -A p n: the contact force on the tissue, with a minus sign.
    f_int->segment<3>(3 * nodes_[k]) -= area * (s.pressure * s.normal + s.traction);
    sum += area / (2 * penalty_) * (s.pressure * s.pressure - lambda_[k] * lambda_[k]);
  }
  if (energy != nullptr) *energy += sum;
}

void RigidContact::AddTangent(const Eigen::VectorXd& u, const DofMap& dofs, LinearSystem* system,
                              const AssemblyOptions& options) const {
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  bool inserted = false;
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const NodeState s = Evaluate(k, u);
    if (s.pressure <= 0) continue;
    const double area = areas_[k];
    const Eigen::Matrix3d nn = s.normal * s.normal.transpose();
    // d(-A p n)/dx with dp/dx = -penalty n (dg/dx = n for every shape).
    Eigen::Matrix3d block = area * penalty_ * nn;
    if (body_.shape == ContactSpec::Shape::kSphere && s.distance > 0 &&
        !options.drop_pressure_stiffness) {
      // The normal turns with the node: dn/dx = (I - n n^T) / |x - c|.
      block -= area * s.pressure / s.distance * (identity - nn);
    }
    if (friction_ > 0) {
      if (s.sliding) {
        const Eigen::Vector3d e = s.traction / s.traction.norm();
        block += area * penalty_ * (friction_ * s.pressure / s.trial_norm) *
                 (identity - nn - e * e.transpose());
      } else {
        block += area * penalty_ * (identity - nn);
      }
    }
    const Eigen::Vector3d force = area * (s.pressure * s.normal + s.traction);  // on the tissue
    const int node = nodes_[k];
    // A partitioned tangent holds its rank's columns only (the right-hand
    // side is whole by now).
    const bool column = options.own_nodes == nullptr || (*options.own_nodes)[node];
    for (int i = 0; i < 3; ++i) {
      const int fi = dofs.free_index(3 * node + i);
      if (fi < 0) continue;
      system->rhs(fi) += force(i);  // rhs = -f_int
      for (int j = 0; j < 3; ++j) {
        const int dof_j = 3 * node + j;
        const int fj = dofs.free_index(dof_j);
        if (fj >= 0) {
          if (!column) continue;
          system->k.coeffRef(fi, fj) += block(i, j);
          inserted = inserted || !system->k.isCompressed();
        } else if (options.lift_prescribed) {
          system->rhs(fi) -= block(i, j) * dofs.prescribed_value(dof_j);
        }
      }
    }
  }
  // Every element's pattern holds its nodes' own blocks, so nothing is
  // inserted unless the node belongs to no element; then compress again.
  if (inserted) system->k.makeCompressed();
}

bool RigidContact::Augment(const Eigen::VectorXd& u) {
  std::vector<double> pressure(nodes_.size());
  double deepest = 0;
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const NodeState s = Evaluate(k, u);
    pressure[k] = s.pressure;
    if (s.candidate) deepest = std::max(deepest, -s.gap);
  }
  if (deepest <= tolerance_) return false;
  lambda_ = std::move(pressure);
  return true;
}

void RigidContact::Commit(const Eigen::VectorXd& u) {
  if (friction_ <= 0) return;
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const NodeState s = Evaluate(k, u);
    if (s.pressure <= 0) {
      stick_[k] = s.relative;  // free: it will stick where it touches down
    } else if (s.sliding) {
      stick_[k] = s.relative + s.traction / penalty_;  // elastic slip -t / penalty remains
    }
  }
}

std::vector<double> RigidContact::SaveState() const {
  std::vector<double> values(lambda_);
  for (const Eigen::Vector3d& s : stick_) values.insert(values.end(), s.data(), s.data() + 3);
  return values;
}

Status RigidContact::RestoreState(const std::vector<double>& values) {
  if (values.size() != 4 * nodes_.size()) {
    return Status::InvalidArgument("contact", "its state holds " + std::to_string(values.size()) +
                                                  " numbers where this contact's " +
                                                  std::to_string(nodes_.size()) + " nodes keep " +
                                                  std::to_string(4 * nodes_.size()));
  }
  const std::size_t n = nodes_.size();
  lambda_.assign(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(n));
  for (std::size_t k = 0; k < n; ++k) stick_[k] = Eigen::Vector3d(&values[n + 3 * k]);
  return Status::Ok();
}

ContactMeasure RigidContact::Measure(const Eigen::VectorXd& u) const {
  ContactMeasure m;
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const NodeState s = Evaluate(k, u);
    if (s.candidate) m.penetration = std::max(m.penetration, -s.gap);
    if (s.pressure <= 0) continue;
    m.force -= areas_[k] * (s.pressure * s.normal + s.traction);
    m.area += areas_[k];
    ++m.nodes_in_contact;
  }
  return m;
}

std::unique_ptr<FiniteStrainModel> WithContact(const FiniteStrainModel& body,
                                               std::vector<const RigidContact*> contacts) {
  return std::make_unique<ContactModel>(body, std::move(contacts));
}

double DefaultContactPenalty(double shear_modulus_pa, double element_size_m, double factor) {
  return factor * shear_modulus_pa / element_size_m;
}

Status PlaceTouching(const Mesh& mesh, const FaceSet& set, RigidBody* body) {
  const Eigen::Vector3d d = body->axis.normalized();
  // For each node the shift along d at which it would first touch; the
  // body moves by the smallest (a negative shift moves it back).
  double shift = INFINITY;
  for (int a : set.nodes) {
    const Eigen::Vector3d r = mesh.nodes.row(a).transpose() - body->position;
    const double along = r.dot(d);
    const double off_axis = (r - along * d).norm();
    switch (body->shape) {
      case ContactSpec::Shape::kFlatPunch:
      case ContactSpec::Shape::kCylinderFlat:
        if (off_axis <= body->radius) shift = std::min(shift, along);
        break;
      case ContactSpec::Shape::kCylinderRounded:
        // The hemisphere's centre lies R behind the pole at the position.
        if (off_axis <= body->radius) {
          shift = std::min(shift, along + body->radius -
                                      std::sqrt(body->radius * body->radius - off_axis * off_axis));
        }
        break;
      case ContactSpec::Shape::kSphere:
        // |r - s d| = R at s = along - sqrt(R^2 - off^2), the first touch.
        if (off_axis <= body->radius) {
          shift =
              std::min(shift, along - std::sqrt(body->radius * body->radius - off_axis * off_axis));
        }
        break;
      case ContactSpec::Shape::kPlane:
        shift = std::min(shift, along);
        break;
      case ContactSpec::Shape::kNone:
        break;
    }
  }
  if (!std::isfinite(shift)) {
    return Status::FailedPrecondition(
        "no node of the set lies in the rigid body's path along its axis: move position_mm over "
        "the surface it should touch");
  }
  body->position += shift * d;
  return Status::Ok();
}

}  // namespace pba
