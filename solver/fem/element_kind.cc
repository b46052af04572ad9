#include "fem/element_kind.h"

#include <cstdio>
#include <cstdlib>

namespace pba {
namespace {

using V = ElementKind::Volumetric;

// name, nodes, points, volumetric, linear, finite strain, explicit, history,
// explicit form, Abaqus type.
constexpr ElementKind kKinds[] = {
    {ElementType::kTet4, "TET4", 4, 1, V::kPointwise, true, true, true, true, "TET4", "C3D4"},
    {ElementType::kTet4Anp, "TET4_ANP", 4, 1, V::kNodalAverage, false, true, true, true, "TET4_ANP",
     "C3D4"},
    {ElementType::kTet10, "TET10", 10, 4, V::kPointwise, true, true, false, false, "", "C3D10"},
    {ElementType::kHex8, "HEX8", 8, 8, V::kMeanDilatation, true, true, true, false,
     "HEX8 (one point, hourglass control)", "C3D8"},
    {ElementType::kHex8Full, "HEX8_FULL", 8, 8, V::kPointwise, true, true, false, false, "",
     "C3D8"},
    {ElementType::kTet10Md, "TET10_MD", 10, 4, V::kMeanDilatation, false, true, false, false, "",
     "C3D10"},
};

}  // namespace

std::span<const ElementKind> ElementKinds() { return kKinds; }

const ElementKind& KindOf(ElementType type) {
  for (const ElementKind& kind : kKinds) {
    if (kind.type == type) return kind;
  }
  std::fprintf(stderr, "pba: KindOf(kDefault): the element type was not resolved\n");
  std::abort();
}

const char* ElementName(ElementType element) {
  if (element == ElementType::kDefault) return "DEFAULT";
  return KindOf(element).name;
}

}  // namespace pba
