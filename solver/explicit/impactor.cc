#include "explicit/impactor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {
namespace {

// Radial unit vector of r off the axis d (any perpendicular when on it).
Eigen::Vector3d Radial(const Eigen::Vector3d& r, const Eigen::Vector3d& d, double* rho) {
  const Eigen::Vector3d off = r - r.dot(d) * d;
  *rho = off.norm();
  if (*rho > 0) return off / *rho;
  const Eigen::Vector3d any =
      std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return (any - any.dot(d) * d).normalized();
}

}  // namespace

Impactor::Impactor(const Contact& contact, std::vector<int> candidates, const Eigen::VectorXd& mass,
                   double dt)
    : name_(contact.name),
      shape_(contact.body.shape),
      position_(contact.body.position),
      axis_(contact.body.axis.normalized()),
      motion_(contact.body.motion),
      radius_(contact.body.radius),
      nodes_(std::move(candidates)) {
  const double factor = contact.penalty_factor;
  k_.resize(nodes_.size());
  k_min_ = std::numeric_limits<double>::infinity();
  k_max_ = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    k_[i] = 0.1 * factor * mass(nodes_[i]) / (dt * dt);
    k_min_ = std::min(k_min_, k_[i]);
    k_max_ = std::max(k_max_, k_[i]);
  }
  if (nodes_.empty()) k_min_ = 0;
}

double Impactor::Depth(const Eigen::Vector3d& c, const Eigen::Vector3d& x,
                       Eigen::Vector3d* normal) const {
  const Eigen::Vector3d r = x - c;
  const double s = r.dot(axis_);
  switch (shape_) {
    case ContactSpec::Shape::kSphere: {
      const double dist = r.norm();
      if (dist >= radius_) return 0;
      *normal = dist > 0 ? Eigen::Vector3d(r / dist) : axis_;
      return radius_ - dist;
    }
    case ContactSpec::Shape::kPlane:
      *normal = axis_;
      return std::max(0.0, -s);
    case ContactSpec::Shape::kFlatPunch: {
      double rho;
      Radial(r, axis_, &rho);
      if (s >= 0 || rho > radius_) return 0;
      *normal = axis_;
      return -s;
    }
    case ContactSpec::Shape::kCylinderFlat: {
      if (s >= 0) return 0;
      double rho;
      const Eigen::Vector3d radial = Radial(r, axis_, &rho);
      if (rho >= radius_) return 0;
      if (-s <= radius_ - rho) {
        *normal = axis_;
        return -s;
      }
      *normal = radial;
      return radius_ - rho;
    }
    case ContactSpec::Shape::kCylinderRounded: {
      if (s >= 0) return 0;
      if (s > -radius_) {
        const Eigen::Vector3d from_centre = r + radius_ * axis_;
        const double dist = from_centre.norm();
        if (dist >= radius_) return 0;
        *normal = dist > 0 ? Eigen::Vector3d(from_centre / dist) : axis_;
        return radius_ - dist;
      }
      double rho;
      const Eigen::Vector3d radial = Radial(r, axis_, &rho);
      if (rho >= radius_) return 0;
      *normal = radial;
      return radius_ - rho;
    }
    default:
      return 0;
  }
}

void Impactor::AddForces(const Mesh& mesh, const Eigen::VectorXd& u, double a,
                         const std::vector<char>& skip, Eigen::VectorXd* f) {
  const Eigen::Vector3d c = Centre(a);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  double deepest = 0;
  int touching = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const int n = nodes_[i];
    if (!skip.empty() && skip[n]) continue;
    const Eigen::Vector3d x = mesh.nodes.row(n).transpose() + u.segment<3>(3 * n);
    Eigen::Vector3d normal;
    const double depth = Depth(c, x, &normal);
    if (depth <= 0) continue;
    const Eigen::Vector3d force = k_[i] * depth * normal;
    f->segment<3>(3 * n) += force;
    total -= force;
    deepest = std::max(deepest, depth);
    ++touching;
  }
  state_.force_on_body = total;
  state_.peak_force = std::max(state_.peak_force, total.norm());
  state_.penetration = deepest;
  state_.nodes_in_contact = touching;
}

}  // namespace pba
