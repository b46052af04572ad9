// Page tokens and page sizes of the atlas store's List* calls. A token is
// opaque to clients: the hex form of "<kind>.v1:<scope>:<key>", where kind
// names the listing, scope the id it lists within (a project or structure;
// 0 for none) and key the sort key of the last item returned. Carrying kind
// and scope means a token from one listing is refused by another instead of
// silently paging through the wrong thing.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

inline constexpr int kDefaultPageSize = 50;
inline constexpr int kMaxPageSize = 1000;

// 0 -> kDefaultPageSize, above kMaxPageSize -> kMaxPageSize, negative refused.
Status NormalisePageSize(int page_size, int* normalised);

std::string EncodePageToken(std::string_view kind, int64_t scope, int64_t key);

// kInvalidArgument (field page_token) unless `token` came from
// EncodePageToken(kind, scope, *key).
Status DecodePageToken(std::string_view token, std::string_view kind, int64_t scope, int64_t* key);

}  // namespace pba
