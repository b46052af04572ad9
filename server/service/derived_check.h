// The commit rule of derived structures (atlas/derived_structure.h): a
// derived structure's recipe may only read structures the project has, or
// derived structures made before it, and not one a merge takes. A create or
// commit of a derived structure is checked against the heads of the
// project's other structures, so the mistake is refused where it is made
// rather than found when a snapshot is meshed. (Two commits racing may
// still make a project whose recipes conflict; composing a snapshot checks
// again and names the structure.)
#pragma once

#include <string>
#include <string_view>

#include "pba/status.h"
#include "store/atlas_store.h"

namespace pba {

// Ok for any format but derived. kInvalidArgument on `field` naming the
// structure the recipe reads and why it cannot; kInternal when a head
// recipe of the project cannot be read.
Status CheckDerivedStructure(AtlasStore& store, const std::string& user, const StructureRef& ref,
                             StructureFormat format, std::string_view content,
                             const std::string& field);

}  // namespace pba
