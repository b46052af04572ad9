// The "billion laughs" in YAML: nine levels of ten aliases to the level
// below, 10^9 leaves from about a kilobyte. Every reader of user YAML
// (scenes, contours, manifests) must refuse it before expanding it.
#pragma once

#include <string>

namespace yaml_bombs {

// Lines "<name>0: &<name>0 <leaf>" then "<name>k: &<name>k [*<name>(k-1) x 10]"
// for k = 1..9; the first alias is on the second line.
inline std::string AliasLevels(const std::string& leaf, const std::string& name = "l") {
  std::string text = name + "0: &" + name + "0 " + leaf + "\n";
  for (int level = 1; level <= 9; ++level) {
    const std::string below = "*" + name + std::to_string(level - 1);
    text += name + std::to_string(level) + ": &" + name + std::to_string(level) + " [";
    for (int k = 0; k < 10; ++k) text += (k > 0 ? ", " : "") + below;
    text += "]\n";
  }
  return text;
}

// Ten-leaf lists of "lol" at the bottom.
inline std::string BillionLaughs() {
  return AliasLevels("[lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]");
}

}  // namespace yaml_bombs
