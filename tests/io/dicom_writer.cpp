// SPDX-License-Identifier: Apache-2.0
// Builds DICOM test input at run time with ITK (a separate translation unit: ITK's bundled
// Eigen must not meet the system Eigen of ido's headers).
#include "dicom_writer.h"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImageSeriesReader.h>
#include <itkImage.h>
#include <itkImageFileWriter.h>
#include <itkMetaDataObject.h>

#include <stdexcept>

namespace ido::test {

void write_tiny_dicom_series(const std::filesystem::path& dir, const std::string& series_uid,
                             const std::string& prefix, int slices) {
  using Image = itk::Image<std::int16_t, 3>;
  for (int s = 0; s < slices; ++s) {
    auto img = Image::New();
    Image::RegionType region;
    region.SetSize({{4, 3, 1}});
    img->SetRegions(region);
    img->Allocate();
    img->SetSpacing(itk::Vector<double, 3>(std::array<double, 3>{0.5, 0.5, 2.0}.data()));
    Image::PointType origin;
    origin[0] = 0.0;
    origin[1] = 0.0;
    origin[2] = 2.0 * s;
    img->SetOrigin(origin);
    img->FillBuffer(static_cast<std::int16_t>(100 + s));
    auto io = itk::GDCMImageIO::New();
    io->KeepOriginalUIDOn();
    itk::MetaDataDictionary dict;
    itk::EncapsulateMetaData<std::string>(dict, "0008|0060", "CT");
    itk::EncapsulateMetaData<std::string>(dict, "0020|000e", series_uid);
    itk::EncapsulateMetaData<std::string>(dict, "0020|000d", series_uid + ".1");
    itk::EncapsulateMetaData<std::string>(dict, "0008|0018", series_uid + ".2." + std::to_string(s + 1));
    itk::EncapsulateMetaData<std::string>(dict, "0020|0013", std::to_string(s + 1));
    itk::EncapsulateMetaData<std::string>(dict, "0020|0032", "0\\0\\" + std::to_string(2 * s));
    itk::EncapsulateMetaData<std::string>(dict, "0020|0037", "1\\0\\0\\0\\1\\0");
    itk::EncapsulateMetaData<std::string>(dict, "0028|0030", "0.5\\0.5");
    img->SetMetaDataDictionary(dict);
    auto writer = itk::ImageFileWriter<Image>::New();
    writer->SetImageIO(io);
    writer->SetInput(img);
    writer->SetFileName((dir / (prefix + std::to_string(s) + ".dcm")).string());
    writer->Update();
  }
}

ItkSeries read_series_with_itk(const std::filesystem::path& dir) {
  using Image = itk::Image<float, 3>;
  auto names = itk::GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(false);
  names->SetDirectory(dir.string());
  const auto uids = names->GetSeriesUIDs();
  if (uids.size() != 1) throw std::runtime_error("read_series_with_itk: expected one series in " + dir.string());
  auto reader = itk::ImageSeriesReader<Image>::New();
  reader->SetImageIO(itk::GDCMImageIO::New());
  reader->SetFileNames(names->GetFileNames(uids.front()));
  reader->Update();
  const auto sz = reader->GetOutput()->GetLargestPossibleRegion().GetSize();
  ItkSeries out{sz[0], sz[1], sz[2], {}};
  const float* p = reader->GetOutput()->GetBufferPointer();
  out.voxels.assign(p, p + sz[0] * sz[1] * sz[2]);
  return out;
}

}  // namespace ido::test
