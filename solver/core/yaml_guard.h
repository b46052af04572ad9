// A pass over YAML (and JSON) text before yaml-cpp builds nodes from it,
// refusing what makes a small file expensive. yaml-cpp keeps an alias
// (*name) as a reference to its anchor (&name), so loading is cheap, but
// every walk over the tree visits each reference again: nine levels of ten
// aliases are 10^9 visits from a few hundred bytes (the "billion laughs").
// yaml-cpp has no switch to refuse aliases, so this pass reads the event
// stream (YAML::Parser::HandleNextDocument) and stops at the first alias.
// It also caps the text size, the node count (yaml-cpp spends some hundred
// bytes per node) and the nesting depth.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

struct YamlLimits {
  size_t max_bytes = size_t{64} << 20;  // text size
  size_t max_nodes = 4'000'000;         // scalars, sequences, maps and nulls
  int max_depth = 64;                   // nested sequences and maps
};

// The first alias or exceeded limit of `text`: `message` names it (empty
// when there is none), `line` is its 1-based line (0 when none applies).
// Malformed YAML passes (yaml-cpp's own load reports it, with its line).
struct YamlProblem {
  int line = 0;
  std::string message;
};
YamlProblem FindYamlProblem(std::string_view text, const YamlLimits& limits = {});

// The same as kInvalidArgument on `field`, the message starting with the
// line ("line 3: YAML aliases (*base) are not accepted: ...").
Status CheckYamlText(std::string_view text, const std::string& field,
                     const YamlLimits& limits = {});

// The text of the file `path`, checked as CheckYamlText checks it before a
// YAML load: kIo when it cannot be read; kInvalidArgument on `field` when it
// holds more than limits.max_bytes (read no further than that) or has a
// problem FindYamlProblem finds.
Status ReadYamlFileText(const std::filesystem::path& path, const std::string& field,
                        std::string* text, const YamlLimits& limits = {});

}  // namespace pba
