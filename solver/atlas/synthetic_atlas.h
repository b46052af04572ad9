// The built-in synthetic brain atlas: a label volume generated purely by
// code, with every one of the 44 labels of ColourTable::Builtin() painted at
// a plausible place. It is SYNTHETIC - shaped after published average sizes,
// not after any brain - and is meant for exercising the plate -> mesh ->
// solve pipeline, not for anatomy or clinical use.
//
// Coordinates [mm]: origin at the anterior commissure, x to the subject's
// right, y anterior, z superior. Every structure is defined for the left
// hemisphere (x < 0) and mirrored in x = 0, so the volume is exactly
// left-right symmetric; a structure's label covers both sides.
//
// Sizes: centroids and semi-axes come from the moment ellipsoids of a public
// digital atlas of the human brain (AC origin), as collected in the project's
// domain notes: lateral ventricle, third and fourth ventricles, caudate,
// putamen, globus pallidus, thalamus, hippocampus, nucleus accumbens, corpus
// callosum and the whole brain. Positions and sizes of the other structures
// (gyri, thalamic and hypothalamic nuclei, midbrain nuclei, geniculate and
// mamillary bodies, fornix) are plausible choices of this code.
//
// Shapes and painting order (a later step overwrites an earlier one; steps
// after the first paint only voxels already inside the brain):
//   1. Brain: the ellipsoid centred (2, -29, 5) with semi-axes 67 (x), 93
//      (y), 59 (z), intersected with its mirror image so the hemispheres
//      mirror (it is 130 mm wide, not 134). Inside: White matter, except an
//      interhemispheric fissure (|x| < 1 mm, background) from the top down
//      to just above the corpus callosum (to the base in front of the genu,
//      to z = -22 behind the splenium).
//      Cortical mantle: the voxels within cortex_thickness_mm of the outer
//      surface or of the fissure, parcelled by nearest seed point into the
//      gyri (inferior, middle and medial frontal, middle and inferior
//      temporal, middle and inferior occipital, cuneus, lingual); seeds of
//      "Cortical areas" cover the rest.
//   2. Insula: a thin ellipsoidal plate lateral to the putamen, deep to the
//      lateral cortex.
//   3. Hippocampal gyrus, 4. hippocampus: swept tubes (smoothed polyline
//      centreline with a radius profile; inside = distance to the
//      centreline <= local radius) curving from the temporal lobe up and
//      back; the gyrus runs below and medial to the hippocampus.
//   5. Putamen; 6. globus pallidus (one ellipsoid split by a sagittal plane
//      into the lateral and medial parts).
//   7. Caudate nucleus: head ellipsoid plus a C-shaped tube (body over the
//      thalamus, tail down into the roof of the temporal horn).
//   8. Nucleus accumbens.
//   9. Corpus callosum: an arched slab - a sagittal tube from rostrum over
//      genu, body and splenium, 7-10 mm thick, extruded to |x| <= 20 mm and
//      drooping laterally.
//  10. Ventricles: C-shaped lateral ventricles (frontal horn, body, atrium,
//      temporal horn, plus the occipital horn) as tubes, the fourth
//      ventricle as an ellipsoid.
//  11. Fornix: a thin tube from the hippocampal tail up over the thalamus,
//      forward under the callosum and down (the column) to the mamillary
//      body.
//  12. Thalamus: an ellipsoid (InsideSyntheticThalamus) parcelled by nearest
//      seed into the eleven "Thalamus: ..." nuclei.
//  13. Third ventricle (Ventricles): a thin midline ellipsoid.
//  14. Hypothalamus (POL, SO, VM, LAT: one small ellipsoid below and in
//      front of the thalamus parcelled by nearest seed), mamillary bodies.
//  15. Subthalamic nucleus, substantia nigra, red nucleus (split at its
//      centre height into top and bottom), lateral and medial geniculate
//      bodies: small ellipsoids.
#pragma once

#include <Eigen/Core>

#include "atlas/label_volume.h"
#include "pba/status.h"

namespace pba {

struct SyntheticAtlasOptions {
  // Edge of the cubic voxels [mm]; the grid has a voxel centred on x = 0.
  double voxel_size_mm = 1.0;
  // Thickness of the cortical mantle [mm].
  double cortex_thickness_mm = 5.5;

  // voxel_size_mm in [0.25, 5]; cortex_thickness_mm in [1, 15].
  Status Validate() const;
};

// The atlas on a grid covering the brain plus a voxel margin. Labels are the
// ids of ColourTable::Builtin(). Expects options.Validate().ok() (checked;
// aborts otherwise).
LabelVolume MakeSyntheticAtlas(const SyntheticAtlasOptions& options);

// The brain region of step 1 (before the fissure is cut) [mm].
bool InsideSyntheticBrain(const Eigen::Vector3d& p_mm);

// The thalamus ellipsoid of step 12 (either hemisphere): centred
// (-9, -25, 4), semi-axes 20 mm along the long axis (anterior, turned 15
// degrees so its front end is medial), 12 mm across it, 9 mm vertical.
bool InsideSyntheticThalamus(const Eigen::Vector3d& p_mm);

}  // namespace pba
