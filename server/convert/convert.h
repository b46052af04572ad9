// Conversions between the pba.v1 messages and the solver's own types.
// The only place (with the server) where protobuf meets the solver.
#pragma once

#include <string>
#include <vector>

#include "pba/solve.h"
#include "pba/status.h"
#include "pba/v1/scene.pb.h"
#include "pba/v1/summary.pb.h"

namespace pba {

// Translates a Scene message into a SceneSpec. Fails with kInvalidArgument
// naming the field path when a required oneof is not set or an enum value is
// unknown. Does not check ranges: call ValidateScene() (or
// ValidateSceneProto()) for that.
Status SceneFromProto(const v1::Scene& scene, SceneSpec* spec);

// SceneFromProto() followed by ValidateScene(): everything a server checks
// before it accepts a scene.
// With `ranks` > 1, also whether the scene can share its solves between
// that many MPI processes (ValidateSceneOnRanks).
// `atlas_structures`: the names of the atlas the scene is built from when
// it is not the synthetic one (a snapshot's structures), which every
// structure the scene names is checked against (AtlasSpec::known_structures).
Status ValidateSceneProto(const v1::Scene& scene, int ranks = 1,
                          const std::vector<std::string>& atlas_structures = {});

// The summary message written to summary.json.
v1::Summary SummaryToProto(const Summary& summary);

}  // namespace pba
