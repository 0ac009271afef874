// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"

/// Synthetic CT-like volumes with ground-truth labels, for testing segmentation.
namespace ido::segment {

/// Which synthetic shape to build. Every shape lives in a fixed physical box (mm), so a
/// different spacing changes the voxel count, not the anatomy.
enum class PhantomKind {
  Sphere,          ///< contrasted ball, radius 15 mm (χ = 2)
  Torus,           ///< contrasted ring, radii 16 and 5 mm (genus 1, χ = 0)
  YBifurcation,    ///< trunk (r 5 mm) splitting into two branches (r 4 mm) (χ = 2)
  UTube,           ///< a hairpin tube (r 5 mm) whose two straight arms touch along a line:
                   ///< the label is ONE genus-0 object (χ = 2), the bend has no hole
  VesselNearBone,  ///< vessel (r 5 mm) beside a cortical bone cylinder, separated by a gap of
                   ///< exactly one voxel of soft tissue along x; label = vessel only (χ = 2)
  VesselTree,      ///< tapering tree: trunk 6 → 5 mm, two branches 4.5 → 3.5 mm, three
                   ///< twigs 3 → 2 mm (χ = 2)
  Vertebra,        ///< vertebral body (cortical shell, cancellous core), pedicles and lamina
                   ///< closing a ring around the spinal canal, spinous process; label = bone
                   ///< (genus 1, χ = 0)
  SpineAorta,      ///< the vertebra (label 2) beside the aorta (label 1, r 9 mm): the pipeline
                   ///< demo's CT; seeds for both, and a pedicle-screw drill path
  CalcifiedVessel, ///< vessel (r 6 mm) with four calcified plaques on its wall, both label 1,
                   ///< and a bone cylinder (label 2) 2 mm beside it: for add_calcification
  // Leak phantoms (issue 27): the labelled organ touches an unlabelled neighbour that a
  // band around the organ's grey level also accepts. Label 1 = the intended organ only.
  ValveChamber,      ///< vessel (r 6 mm, label 1) opening through a valve ring (lumen r 4.5 mm)
                     ///< into an unlabelled chamber of the same 350 HU, like the aorta leaving
                     ///< the left ventricle (χ = 2)
  VeinInParenchyma,  ///< vein (r 10 mm, 140 HU, label 1) along z, partly embedded in an
                     ///< unlabelled liver-like ellipsoid of 125 HU, like the IVC behind the
                     ///< liver (χ = 2)
  VertebraStack,     ///< three vertebrae along z with 3.5 mm discs (80 HU), a cortical
                     ///< osteophyte bridge across each disc and 0.8 mm facet-joint gaps;
                     ///< label 1 = the middle vertebra only (genus 1, χ = 0)
  LungSeed,          ///< air-filled airway (r 6 mm, −1000 HU, label 1) from the mediastinum
                     ///< into a lung of −850 HU with a few 40 HU vessels (χ = 2)
};

/// The kinds the accuracy suite runs over, in declaration order: Sphere to Vertebra. The
/// two-label kinds (SpineAorta, CalcifiedVessel) and the leak phantoms (ValveChamber to
/// LungSeed) are left out; parse_phantom_kind accepts them all.
[[nodiscard]] const std::vector<PhantomKind>& all_phantom_kinds();

/// The lower-case name of a kind ("sphere", "torus", "y-bifurcation", "u-tube",
/// "vessel-near-bone", "vessel-tree", "vertebra", "spine-aorta", "calcified-vessel",
/// "valve-chamber", "vein-in-parenchyma", "vertebra-stack", "lung-seed").
[[nodiscard]] std::string_view phantom_kind_name(PhantomKind kind);

/// Parses a kind name (case-insensitive; '_' and '-' are interchangeable).
/// @throws ido::InvalidInput naming the unknown kind and listing the valid ones.
[[nodiscard]] PhantomKind parse_phantom_kind(std::string_view name);

/// Hounsfield units used by the phantoms.
struct PhantomIntensities {
  double soft_tissue_hu = 40.0;   ///< background
  double fat_hu = -100.0;         ///< outside the elliptic "body" cylinder, in the corners
  double vessel_hu = 350.0;       ///< contrast-enhanced blood
  double cortical_hu = 1200.0;    ///< compact bone
  double cancellous_hu = 250.0;   ///< trabecular bone
  double vein_hu = 140.0;         ///< portal-venous vein (vein-in-parenchyma)
  double parenchyma_hu = 125.0;   ///< liver-like parenchyma, 15 HU below the vein
  double disc_hu = 80.0;          ///< intervertebral disc (vertebra-stack)
  double lung_hu = -850.0;        ///< aerated lung parenchyma (lung-seed)
  double air_hu = -1000.0;        ///< air in the airway (lung-seed)
};

/// Tunables of make_phantom.
struct PhantomOptions {
  Vec3 spacing_mm{1.0, 1.0, 1.0};  ///< voxel size (anisotropic allowed), each in (0, 10]
  double noise_hu = 0.0;           ///< σ of additive Gaussian noise (HU), ≥ 0
  double blur_voxels = 0.0;        ///< σ of the Gaussian blur, in voxels along each axis, ≥ 0
  std::uint64_t seed = 1;          ///< noise seed; same seed → identical volume
  int supersampling = 4;           ///< partial-volume samples per axis in boundary voxels (1–8)
  PhantomIntensities intensities{};  ///< tissue HU values
  bool threaded = true;            ///< build with oneTBB (output identical either way)
};

/// A synthetic CT volume with its ground truth.
struct Phantom {
  PhantomKind kind = PhantomKind::Sphere;
  image::Volume<float> ct_hu;          ///< CT-like intensities (HU)
  image::Volume<std::uint8_t> labels;  ///< ground truth on the same grid: 1 = object
  std::vector<Vec3> seeds_mm;          ///< seed points inside the object (world mm)
  std::vector<Index3> seeds_voxel;
  /// Label (value in `labels`) of the object each seed lies in; 1 for single-object kinds.
  std::vector<int> seed_labels;
  /// A drill trajectory (polyline, world mm) for kinds with bone (a pedicle-screw path for
  /// the vertebrae); empty otherwise.
  std::vector<Vec3> drill_path_mm;     ///< the same seeds as voxel indices (nearest voxel)
  /// Euler characteristic of the truth's boundary surface (2 − 2·genus per component),
  /// computed from the label voxels (see mask_euler_characteristic in metrics.h).
  int truth_euler_characteristic = 2;
  std::string description;  ///< one line: shape, sizes, intensities
  double object_hu = 0.0;      ///< intensity of the labelled object's bulk (HU)
  double background_hu = 0.0;  ///< intensity around it (HU)
  /// |object − background| (HU); noise "20 % of the contrast" means noise_hu = 0.2·this.
  double contrast_hu = 0.0;
  /// Analytic volume of the labelled shape (mm³) where known in closed form, else 0.
  double analytic_volume_mm3 = 0.0;
};

/// Builds a phantom: each voxel's intensity is the mean of the tissue intensities at
/// supersampling³ points inside it (partial volume; voxels farther than their half-diagonal
/// from every tissue boundary take their centre's tissue), then the blur, then the noise
/// (Box–Muller on a SplitMix64 stream per slice, so the output is bit-identical for a seed
/// with or without threads). A voxel is labelled when more than half of its samples lie in
/// the object (an exact tie goes to the centre sample). The grid's origin is half a voxel, so the physical box is [0, extent] mm.
/// @throws ido::InvalidInput for a bad option (spacing, noise, blur, supersampling).
[[nodiscard]] Phantom make_phantom(PhantomKind kind, const PhantomOptions& options = {});

}  // namespace ido::segment
