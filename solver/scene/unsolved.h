// Scene fields that are read and checked but that the solver and the
// Abaqus export do not act on yet: a scene using them is refused before
// meshing rather than answered without them.
#pragma once

#include <string>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

// FailedPrecondition naming the first such field, e.g. "contacts: rigid
// contact is not solved by this version"; `action` is "solved" or
// "exported".
Status RefuseUnsupportedFields(const SceneSpec& scene, const std::string& action);

// True when a material of the scene relaxes (its viscoelastic section),
// which a static analysis answers with the instantaneous response.
bool AnyViscoelastic(const SceneSpec& scene);

}  // namespace pba
