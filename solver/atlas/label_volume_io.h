// Label volumes as NIfTI-1 (.nii, .nii.gz) and NRRD (.nrrd) files, the
// formats atlases are exchanged in (ITK-SNAP, 3D Slicer, FSL, ANTs). A label
// table (id -> name, colour) travels separately as the CSV of
// colour_table.h; ITK-SNAP and Slicer colour tables are not read.
//
// Orientation. LabelVolume axes are the project's world axes: x to the
// subject's right, y anterior, z superior (RAS), millimetres, spacing > 0,
// origin_mm = centre of voxel (0, 0, 0) (label_volume.h). A file's
// index -> world map must be axis-aligned: a signed permutation of the
// axes times positive spacings (flips such as LAS or LPS, and axis orders
// such as a coronal stack, are fine); an oblique map (a direction with
// more than one non-zero component, relative tolerance 1e-4) is rejected.
// Flipped or permuted axes are reordered on reading so the volume comes out
// in RAS with positive spacing; the origin becomes the centre of the voxel
// with the lowest x, y and z.
//
// Labels are uint16 on output. On input any integer type up to 64 bits,
// float32 and float64 are converted; a value that is negative, above 65535
// or not an integer is an error naming the value and its voxel.
//
// Writes are atomic: the file is written to a temporary file in the target
// directory, synced, and renamed over the target; on failure nothing is
// left behind. Reads and writes print nothing.
#pragma once

#include <filesystem>

#include "atlas/label_volume.h"
#include "pba/status.h"

namespace pba {

// Bounds the readers check a header against before allocating anything for
// its data, so that a small hostile file cannot cost gigabytes: at most
// kMaxLabelVolumeVoxels voxels (512^3, a 0.5 mm grid over a 256 mm cube);
// the data must be present in the file (a raw file at least as long as the
// header says, read in pieces so memory follows the bytes actually there);
// gzip data may announce at most kMaxGzipRatio times the compressed size
// (deflate cannot expand more than 1032:1) and are inflated in pieces, never
// past what the header announces.
inline constexpr size_t kMaxLabelVolumeVoxels = size_t{1} << 27;
inline constexpr double kMaxGzipRatio = 1100;

// NIfTI-1 through the NIfTI reference library (nifti1_io, Debian
// libnifti2-dev, with znzlib for gzip). A name ending in ".nii.gz" is
// written gzip-compressed, ".nii" plain; anything else is an error.
// Written: datatype uint16, scl_slope 1, scl_inter 0, xyzt_units mm,
// qform and sform (code 1, scanner) both the diagonal map of the volume;
// spacing and origin are stored as float32 (NIfTI-1 has no wider field).
//
// Read: the header through the library, the data by this code (through
// znzlib; the library accepts data shorter than the header says, this code
// rejects it); dimensions beyond the third must be 1; the world map is the sform
// when sform_code > 0, else the qform when qform_code > 0, else (neither
// set: "analyze" method 1) the diagonal pixdim with the origin at voxel 0.
// NIfTI's world is RAS, so it maps to the project axes directly. Spatial
// units m, mm and um are converted to mm (unknown units are taken as mm).
// scl_slope must be 0 or 1 and scl_inter 0 (a scaled image is not a label
// image). The library keeps global state (its debug level, set to 0 on every
// call so it prints nothing); calls from several threads race on it only
// for that setting.
Status WriteNifti(const LabelVolume& volume, const std::filesystem::path& file);

// Whether the file starts with the gzip magic bytes (a .nii.gz whatever it
// is called: uploads and blobs have no extension).
bool HasGzipMagic(const std::filesystem::path& file);

// ReadNifti or ReadNrrd by the file's extension (.nii, .nii.gz, .nrrd);
// another is kInvalidArgument on `field` naming the file.
Status ReadLabelVolume(const std::filesystem::path& file, const std::string& field,
                       LabelVolume* volume);
Status ReadNifti(const std::filesystem::path& file, LabelVolume* volume);

enum class NrrdEncoding { kRaw, kGzip };

// NRRD (format 4, http://teem.sourceforge.net/nrrd/format.html) by this
// code, not teem's nrrd: teem reports errors through its "biff" message
// store, global and not thread-safe, in a multi-threaded server; and the
// subset below is small. Written: "NRRD0004", type uint16, dimension 3,
// space right-anterior-superior, sizes, diagonal space directions, space
// origin, endian little, encoding raw or gzip, data attached.
//
// Read: dimension 3; type int8, uint8, int16, uint16, int32, uint32 (any of
// the format's spellings); encoding raw or gzip (gz); endian little or big;
// attached data only (no "data file"); space right-anterior-superior,
// left-anterior-superior or left-posterior-superior (or RAS, LAS, LPS),
// with space directions and space origin (mm; "space units" other than mm
// are an error) - or no space and "spacings" (origin 0). Directions must be
// axis-aligned as above; "line skip" and "byte skip" other than 0 are
// errors. Comments and key:=value pairs are ignored.
Status WriteNrrd(const LabelVolume& volume, const std::filesystem::path& file,
                 NrrdEncoding encoding = NrrdEncoding::kGzip);
Status ReadNrrd(const std::filesystem::path& file, LabelVolume* volume);

}  // namespace pba
