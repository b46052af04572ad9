// The file formats a structure's geometry comes in: the one list, shared by
// structure sets (atlas/structure_set.h), pba-atlas and the server's store,
// which keeps the names below in pba.db.
#pragma once

#include <string_view>

namespace pba {

// kDerived: no geometry of its own, a label step over the set's other
// structures (derived_structure.h), as YAML.
enum class StructureFormat { kContours, kNifti, kStl, kObj, kVtk, kDerived };

// "contours_json", "nifti", "stl", "obj", "vtk", "derived": the words of a structure
// set's manifest and of the store's database.
inline const char* StructureFormatName(StructureFormat format) {
  switch (format) {
    case StructureFormat::kContours:
      return "contours_json";
    case StructureFormat::kNifti:
      return "nifti";
    case StructureFormat::kStl:
      return "stl";
    case StructureFormat::kObj:
      return "obj";
    case StructureFormat::kVtk:
      return "vtk";
    case StructureFormat::kDerived:
      return "derived";
  }
  return "unknown";
}

// The file name extension the readers go by: ".json", ".nii.gz" (".nii"
// for a NIfTI that is not gzip-compressed), ".stl", ".obj", ".vtk", ".yaml".
inline const char* StructureFormatExtension(StructureFormat format, bool gzipped) {
  switch (format) {
    case StructureFormat::kContours:
      return ".json";
    case StructureFormat::kNifti:
      return gzipped ? ".nii.gz" : ".nii";
    case StructureFormat::kStl:
      return ".stl";
    case StructureFormat::kObj:
      return ".obj";
    case StructureFormat::kVtk:
      return ".vtk";
    case StructureFormat::kDerived:
      return ".yaml";
  }
  return "";
}

// False, leaving *format alone, for any other word.
inline bool ParseStructureFormat(std::string_view name, StructureFormat* format) {
  for (StructureFormat f :
       {StructureFormat::kContours, StructureFormat::kNifti, StructureFormat::kStl,
        StructureFormat::kObj, StructureFormat::kVtk, StructureFormat::kDerived}) {
    if (name == StructureFormatName(f)) {
      *format = f;
      return true;
    }
  }
  return false;
}

}  // namespace pba
