// SPDX-License-Identifier: Apache-2.0
// ITK level-set peers for bench_segment (the only file of the benchmark that includes ITK).
// The pipelines follow the ITK Software Guide's segmentation examples: a fast-marching
// distance from the seed minus the initial radius is the initial level set; the output level
// set is inside where ≤ 0.
#include "itk_level_set_peer.h"

#include <algorithm>
#include <cstring>

#include <itkFastMarchingImageFilter.h>
#include <itkGeodesicActiveContourLevelSetImageFilter.h>
#include <itkGradientMagnitudeRecursiveGaussianImageFilter.h>
#include <itkImage.h>
#include <itkSigmoidImageFilter.h>
#include <itkThresholdSegmentationLevelSetImageFilter.h>

namespace ido::bench {
namespace {

using Image = itk::Image<float, 3>;

Image::Pointer to_itk(const PeerImage& in) {
  auto img = Image::New();
  Image::RegionType region;
  Image::SizeType size;
  Image::SpacingType spacing;
  Image::PointType origin;
  Image::DirectionType direction;
  for (unsigned a = 0; a < 3; ++a) {
    size[a] = static_cast<itk::SizeValueType>(in.size[a]);
    spacing[a] = in.spacing[a];
    origin[a] = in.origin[a];
    for (unsigned b = 0; b < 3; ++b) direction[a][b] = in.direction[3 * a + b];
  }
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(spacing);
  img->SetOrigin(origin);
  img->SetDirection(direction);
  img->Allocate();
  const std::size_t n = static_cast<std::size_t>(in.size[0] * in.size[1] * in.size[2]);
  std::memcpy(img->GetBufferPointer(), in.voxels, n * sizeof(float));
  return img;
}

// Signed distance from the seed minus the initial radius (fast marching at unit speed),
// computed up to a few radii: the initial level set of both filters.
Image::Pointer initial_level_set(const Image::Pointer& like, const PeerOptions& o) {
  using FastMarching = itk::FastMarchingImageFilter<Image, Image>;
  auto fm = FastMarching::New();
  auto seeds = FastMarching::NodeContainer::New();
  FastMarching::NodeType node;
  Image::IndexType idx;
  for (unsigned a = 0; a < 3; ++a) idx[a] = static_cast<itk::IndexValueType>(o.seed_index[a]);
  node.SetIndex(idx);
  node.SetValue(-o.initial_radius_mm);
  seeds->Initialize();
  seeds->InsertElement(0, node);
  fm->SetTrialPoints(seeds);
  fm->SetSpeedConstant(1.0);
  fm->SetOutputRegion(like->GetLargestPossibleRegion());
  fm->SetOutputSpacing(like->GetSpacing());
  fm->SetOutputOrigin(like->GetOrigin());
  fm->SetOutputDirection(like->GetDirection());
  fm->SetStoppingValue(4.0 * o.initial_radius_mm + 10.0);
  fm->Update();
  return fm->GetOutput();
}

template <class Filter>
PeerResult collect(Filter& f, std::size_t n) {
  PeerResult r;
  const float* out = f.GetOutput()->GetBufferPointer();
  r.inside.resize(n);
  for (std::size_t i = 0; i < n; ++i) r.inside[i] = out[i] <= 0.0f ? 1 : 0;
  r.iterations = static_cast<int>(f.GetElapsedIterations());
  r.rms_change = f.GetRMSChange();
  return r;
}

}  // namespace

PeerResult itk_threshold_level_set(const PeerImage& image, const PeerOptions& o) {
  const Image::Pointer ct = to_itk(image);
  using Filter = itk::ThresholdSegmentationLevelSetImageFilter<Image, Image>;
  auto f = Filter::New();
  f->SetInput(initial_level_set(ct, o));
  f->SetFeatureImage(ct);
  f->SetLowerThreshold(o.lower);
  f->SetUpperThreshold(o.upper);
  f->SetPropagationScaling(o.propagation_scaling);
  f->SetCurvatureScaling(o.curvature_scaling);
  f->SetMaximumRMSError(o.max_rms_change);
  f->SetNumberOfIterations(static_cast<itk::IdentifierType>(o.max_iterations));
  f->SetIsoSurfaceValue(0.0);
  f->Update();
  return collect(*f, ct->GetPixelContainer()->Size());
}

PeerResult itk_geodesic_active_contour(const PeerImage& image, const PeerOptions& o) {
  const Image::Pointer ct = to_itk(image);
  auto grad = itk::GradientMagnitudeRecursiveGaussianImageFilter<Image, Image>::New();
  grad->SetInput(ct);
  grad->SetSigma(o.gradient_sigma_mm);
  auto sigmoid = itk::SigmoidImageFilter<Image, Image>::New();
  sigmoid->SetInput(grad->GetOutput());
  sigmoid->SetOutputMinimum(0.0f);
  sigmoid->SetOutputMaximum(1.0f);
  sigmoid->SetAlpha(o.sigmoid_alpha);
  sigmoid->SetBeta(o.sigmoid_beta);
  sigmoid->Update();
  using Filter = itk::GeodesicActiveContourLevelSetImageFilter<Image, Image>;
  auto f = Filter::New();
  f->SetInput(initial_level_set(ct, o));
  f->SetFeatureImage(sigmoid->GetOutput());
  f->SetPropagationScaling(o.propagation_scaling);
  f->SetCurvatureScaling(o.curvature_scaling);
  f->SetAdvectionScaling(o.advection_scaling);
  f->SetMaximumRMSError(o.max_rms_change);
  f->SetNumberOfIterations(static_cast<itk::IdentifierType>(o.max_iterations));
  f->Update();
  return collect(*f, ct->GetPixelContainer()->Size());
}

}  // namespace ido::bench
