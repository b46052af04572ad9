// Pictures of an atlas a person can look at (8-bit RGB PNG, png_io.h): the
// plates as one contact sheet, and cuts through the built mesh coloured by
// structure, with the elements' edges and the source's contours over them -
// the thesis's comparison of mesh sections against the plates, by eye.
//
// Contact sheet. The plates tiled in a grid of ceil(sqrt(n)) columns,
// bottom plate first, left to right, then top to bottom; each tile is the
// plate in its colours (background black) with a caption band under it
// giving its height ("z -16 mm"); tiles and bands are separated by a grey
// gap. A stack too wide for kMaxSheetWidth is subsampled: every step-th
// pixel of every step-th row (nearest, so the colours stay exact).
//
// Mesh cut. The plane of one axis held constant, seen as
//   axial    (z = const): from above, +x (the subject's right) to the
//            right, +y (anterior) up - as the plates;
//   coronal  (y = const): from behind, +x to the right, +z up, so the
//            right hemisphere is on the same side as in the axial cuts;
//   sagittal (x = const): from the subject's right, +y (anterior) to the
//            right, +z up.
// Coordinates as in synthetic_atlas.h, millimetres (mesh nodes are metres).
// Calling the picture's axes u (to the right) and v (up), the section is a
// grid of square pixels of pixel_mm over the mesh's bounding box in (u, v)
// plus margin_mm; section pixel (c, r) is centred at
//   u = u0 + c * pixel_mm,  v = v0 - r * pixel_mm.
// Axial cuts with plates take the plates' pixel lattice (u0, v0 on the
// plates' pixel centres), so at the plates' pixel size the two grids
// coincide; other cuts put pixel centres at (k + 1/2) * pixel_mm.
// Layers, bottom to top:
//   fill      each pixel centre takes the colour of the region of the
//             tetrahedron containing it (barycentric coordinates >= -1e-9;
//             on a shared face either neighbour), label 0 (kSurroundingTissue)
//             mid grey, outside the mesh black. A 10-node mesh is cut through
//             its corner tetrahedra (straight edges).
//   edges     the polygon (triangle or quadrilateral) each tetrahedron
//             crossing the plane cuts from it, outlined one pixel wide in
//             the fill's colour darkened to kEdgeShade of it: the elements.
//   contours  white (255, 255, 255): the boundaries between labels of the
//             source, resampled onto the section's pixel grid - for an axial
//             cut at a plate's height (within 1e-6 mm) the plate (nearest
//             plate pixel), else the label volume (nearest voxel,
//             LabelVolume::SampleNearest); outside either, background. A
//             pixel is on a contour when its source label differs from the
//             label of its right or lower neighbour, so a contour is one
//             pixel wide, on the left / upper side of the change. Source
//             labels that no region carries are merged first: into one
//             label when a region carries label 0 (the rest merged into
//             "Surrounding tissue"), else into the background (dropped), so
//             the contours are those the mesh was asked to reproduce.
// Around the section a dark frame carries the orientation letters at the
// middle of each side (A / P anterior / posterior, S / I superior /
// inferior, L / R the subject's left / right), and a caption band above it
// the axis, position and contour source ("axial z +2.0 mm, white: plate 14").
// A non-empty notice goes into a tEXt chunk "Comment" (as on the plates).
//
// Files are written atomically (core/atomic_write.h): a temporary file
// beside the target, renamed over it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "atlas/atlas_build.h"
#include "atlas/colour_table.h"
#include "atlas/label_volume.h"
#include "atlas/plates.h"
#include "io/png_io.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

// Widest contact sheet before its tiles are subsampled [pixels].
inline constexpr int kMaxSheetWidth = 4000;
// Colours of the pictures' furniture.
inline constexpr std::array<uint8_t, 3> kGapGrey = {96, 96, 96};             // sheet gaps
inline constexpr std::array<uint8_t, 3> kSurroundingGrey = {128, 128, 128};  // label 0 region
inline constexpr std::array<uint8_t, 3> kFrameColour = {40, 40, 40};         // cut frame
inline constexpr std::array<uint8_t, 3> kContourWhite = {255, 255, 255};     // source contours
inline constexpr std::array<uint8_t, 3> kTextColour = {230, 230, 230};       // captions
// An element edge is drawn in the fill colour times this.
inline constexpr double kEdgeShade = 0.55;

// Where everything sits on a contact sheet (all in pixels).
struct ContactSheetLayout {
  int columns = 0, rows = 0;
  int step = 1;                         // every step-th plate pixel is shown
  int tile_width = 0, tile_height = 0;  // ceil(plate width / step), ...
  int cell_width = 0;                   // the tile, or its caption when wider
  int caption_height = 0;               // the band under each tile
  int gap = 0;                          // between tiles and around the sheet
  int scale = 1;                        // of the caption font
  int width = 0, height = 0;            // the whole sheet
  // Image column and row of the top left pixel of plate p's tile.
  int TileLeft(int p) const { return gap + (p % columns) * (cell_width + gap); }
  int TileTop(int p) const { return gap + (p / columns) * (tile_height + caption_height + gap); }
};

ContactSheetLayout LayOutContactSheet(const PlateStack& plates);

// The contact sheet of `plates` (layout above). Errors: a malformed stack
// (ValidatePlateStack), a label with no colour in plates.colours.
Status RenderPlateContactSheet(const PlateStack& plates, const std::string& notice,
                               RgbImage* image);
Status WritePlateContactSheet(const PlateStack& plates, const std::filesystem::path& png,
                              const std::string& notice);

enum class CutAxis { kAxial, kCoronal, kSagittal };  // z, y, x constant

// "axial", "coronal", "sagittal".
const char* CutAxisName(CutAxis axis);
// 'z', 'y', 'x': the coordinate the cut holds constant.
char CutAxisCoordinate(CutAxis axis);

struct MeshCutOptions {
  CutAxis axis = CutAxis::kAxial;
  double position_mm = 0;  // the constant coordinate [mm]
  double pixel_mm = 0.5;   // section pixel edge [mm], (0, 10]
  double margin_mm = 3;    // around the mesh's bounding box [mm], [0, 100]
  bool edges = true;       // draw the element edges
  std::string notice;      // PNG tEXt "Comment" when not empty

  Status Validate() const;
};

// What the mesh is compared with; either or both may be null.
struct CutSource {
  const LabelVolume* volume = nullptr;
  const PlateStack* plates = nullptr;
};

struct MeshCutPicture {
  RgbImage image;
  CutAxis axis = CutAxis::kAxial;
  double position_mm = 0, pixel_mm = 0;
  double u0_mm = 0, v0_mm = 0;  // u and v of section pixel (0, 0)'s centre [mm]
  int width = 0, height = 0;    // section [pixels]
  int left = 0, top = 0;        // image column and row of section pixel (0, 0)
  // "plate 14" (1-based), "label volume" or "" (no contours).
  std::string contour_source;

  // The point [mm] at the centre of section pixel (c, r).
  Eigen::Vector3d SectionPixelCentreMm(int c, int r) const;
  // The image pixel (column, row) whose section pixel centre is nearest to
  // p projected onto the plane; it may lie outside the section.
  std::array<int, 2> ImagePixel(const Eigen::Vector3d& p_mm) const;
  // The colour of image pixel (column, row).
  std::array<uint8_t, 3> At(int column, int row) const;
};

// Renders the cut described above. region_labels[r] is the colour-table
// label of mesh region r (for a one-region mesh, region_labels[0]).
// Errors (kInvalidArgument naming the field): bad options; a hexahedral or
// empty mesh; element_region or region_labels of the wrong size or out of
// range; a region label other than 0 with no colour; a plane that misses
// the mesh (field "position_mm"; the message names the axis, the position
// and the mesh's extent along the axis).
Status RenderMeshCut(const Mesh& mesh, const std::vector<uint16_t>& region_labels,
                     const ColourTable& colours, const CutSource& source,
                     const MeshCutOptions& options, MeshCutPicture* picture);
Status WriteMeshCut(const Mesh& mesh, const std::vector<uint16_t>& region_labels,
                    const ColourTable& colours, const CutSource& source,
                    const MeshCutOptions& options, const std::filesystem::path& png);

// The file name of a cut: "cut_axial_z+005.0mm.png", "cut_coronal_y-020.0mm.png",
// "cut_sagittal_x+025.0mm.png" (position to 0.1 mm, sign always shown).
std::string CutFileName(CutAxis axis, double position_mm);

struct AtlasPictureOptions {
  double pixel_mm = 0.5;  // of the cuts [mm]
  // The cuts [mm]; when all three are empty, the default cuts:
  //   axial    at three plate heights, the middle plate of the lower,
  //            middle and upper third of the plates within the mesh's
  //            z-range (indices n/6, n/2, 5n/6 rounded down); without
  //            plates at 1/6, 1/2 and 5/6 of the mesh's z-range, to the mm;
  //   coronal  through the centroid of the thalamus (the kept structures
  //            named "Thalamus..." in the label volume), else through the
  //            mesh's centre, to the mm;
  //   sagittal through the right hemisphere, 0.4 of the half-width right of
  //            the mesh's centre, to the mm (x = 26 mm on the synthetic
  //            atlas: the putamen, the lateral ventricle and the
  //            hippocampus).
  std::vector<double> axial_z_mm, coronal_y_mm, sagittal_x_mm;

  Status Validate() const;
};

// Writes into `dir` (created if missing): plates.png, the contact sheet,
// when the result has plates, and a PNG per cut (CutFileName), the contours
// from the result's plates and label volume; a result built from the
// synthetic atlas carries its notice in every file. `written` (optional)
// receives the file names in order. Not atomic as a whole (each file is):
// pba-atlas writes into its staging directory.
Status WriteAtlasPictures(const AtlasBuildResult& result, const std::filesystem::path& dir,
                          const AtlasPictureOptions& options = {},
                          std::vector<std::string>* written = nullptr);

}  // namespace pba
