// SPDX-License-Identifier: Apache-2.0
#include "vtk_flying_edges_peer.h"

#include <vtkFlyingEdges3D.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>
#include <vtkSmartPointer.h>

namespace ido::bench {
namespace {
vtkSmartPointer<vtkImageData>& image() {
  static vtkSmartPointer<vtkImageData> img;
  return img;
}
}  // namespace

std::string vtk_set_threads(int threads) {
  vtkSMPTools::Initialize(threads);
  return std::string(vtkSMPTools::GetBackend()) + ", " +
         std::to_string(vtkSMPTools::GetEstimatedNumberOfThreads()) + " thread(s)";
}

void vtk_prepare(const float* values, int n) {
  auto img = vtkSmartPointer<vtkImageData>::New();
  img->SetDimensions(n, n, n);
  img->SetSpacing(1, 1, 1);
  img->SetOrigin(0, 0, 0);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("distance");
  // Wrap the caller's buffer without copying (save = 1: VTK must not free it).
  scalars->SetArray(const_cast<float*>(values), vtkIdType(n) * n * n, 1);
  img->GetPointData()->SetScalars(scalars);
  image() = img;
}

PeerResult vtk_flying_edges(double iso) {
  vtkNew<vtkFlyingEdges3D> fe;
  fe->SetInputData(image());
  fe->SetValue(0, iso);
  fe->ComputeNormalsOff();
  fe->ComputeGradientsOff();
  fe->ComputeScalarsOff();
  fe->Update();
  return {std::size_t(fe->GetOutput()->GetNumberOfPoints()), std::size_t(fe->GetOutput()->GetNumberOfPolys())};
}

}  // namespace ido::bench
