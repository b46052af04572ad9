// Job ids: "j" and 10 lowercase hex digits (40 random bits), short enough to
// type and read aloud, with collisions rare enough that a retry on insert
// covers them.
#pragma once

#include <string>
#include <string_view>

namespace pba {

std::string NewJobId();

// Whether `id` has the shape NewJobId() produces. Lets the service reject
// garbage before touching the store, and keeps ids safe as folder names.
bool IsWellFormedJobId(std::string_view id);

}  // namespace pba
