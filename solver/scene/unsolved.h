// Scene fields the Abaqus export (one static step, one material) does not
// write: a scene using them is refused before meshing rather than exported
// without them.
#pragma once

#include <string>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

// FailedPrecondition naming the first such field, e.g. "contacts: rigid
// contact is not exported by this version"; `action` names what is
// refused ("exported").
Status RefuseUnsupportedFields(const SceneSpec& scene, const std::string& action);

}  // namespace pba
