// A pba.v1.Summary as text for people: what was modelled, key results,
// speed beside error. Shared by pba-solve and the pba client.
#pragma once

#include <string>

#include "pba/v1/summary.pb.h"

namespace pba::codec {

std::string FormatSummary(const v1::Summary& summary);

}  // namespace pba::codec
