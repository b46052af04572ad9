// A rigid body in solver units: a contact of a static analysis, an
// impactor of an explicit one (scene/problem.h resolves it from the scene's
// contacts).
#pragma once

#include <Eigen/Core>
#include <string>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

// The penalty factor of a contact that gives none: an implicit analysis's
// penalty is this times the tissue's shear modulus over the finest element
// size (analysis/rigid_contact.h), an impactor's this times each node's
// mass over the step squared (explicit/impactor.h).
inline constexpr double kImplicitPenaltyFactor = 100;
inline constexpr double kExplicitPenaltyFactor = 1;

// A rigid body in solver units (a contact of a static analysis, an
// impactor of an explicit one).
struct RigidBody {
  ContactSpec::Shape shape = ContactSpec::Shape::kNone;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // [m], at amplitude 0
  // Direction into the tissue (FLAT_PUNCH, PLANE, the cylinders); any
  // non-zero length.
  Eigen::Vector3d axis = Eigen::Vector3d(0, 0, -1);
  double radius = 0;                                 // [m], all but PLANE: > 0
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();  // [m], displacement at amplitude 1

  // InvalidArgument naming `path` + ".shape", ".axis", ".radius",
  // ".position" or ".motion" when the body is not usable by a static
  // analysis: a cylinder (explicit only), an axis of zero (or non-finite)
  // length for FLAT_PUNCH and PLANE, a radius <= 0 for FLAT_PUNCH and
  // SPHERE, a non-finite position or motion.
  Status Validate(const std::string& path = "contact") const;
};

}  // namespace pba
