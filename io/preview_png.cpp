#include "io/preview_png.hpp"
#include "io/vtk_ready.hpp"

#include "io/atomic_file.hpp"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace phantasm {

void write_preview_png(const std::filesystem::path& path, const ImageGrid& grid,
                       const std::vector<float>& values) {
  make_vtk_ready();
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  if (values.size() != static_cast<std::size_t>(grid.voxel_count()))
    throw std::invalid_argument(path.string() + ": preview of a volume whose size does not match its grid");
  std::vector<float> sorted = values;
  const std::size_t rank = static_cast<std::size_t>(0.995 * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
  const double top = std::max(1e-30, static_cast<double>(sorted[rank]));
  auto at = [&](int i, int j, int k) { return values[voxel_index(grid.dims, i, j, k)]; };
  // Panels: k = nz/2 (i across, j up), j = ny/2 (i across, k up), i = nx/2 (j across, k up).
  const int width = nx + nx + ny, height = std::max(ny, nz);
  std::vector<unsigned char> pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  auto put = [&](int x, int y, float v) {
    const double g = std::clamp(255.0 * v / top, 0.0, 255.0);
    pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)] =
        static_cast<unsigned char>(std::lround(g));
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      put(i, j, at(i, j, nz / 2));
  for (int k = 0; k < nz; ++k)
    for (int i = 0; i < nx; ++i)
      put(nx + i, k, at(i, ny / 2, k));
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      put(2 * nx + j, k, at(nx / 2, j, k));
  // VTK's image origin is the lower left; rows above are higher indices, as wanted.
  write_file_atomically(path, encode_png(width, height, 1, pixels));
}

std::string encode_png(int width, int height, int components, const std::vector<unsigned char>& pixels) {
  make_vtk_ready();
  if (width <= 0 || height <= 0 || components < 1 || components > 4 ||
      pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                           static_cast<std::size_t>(components))
    throw std::invalid_argument("PNG of " + std::to_string(width) + " x " + std::to_string(height) + " x " +
                                std::to_string(components) + " bytes given " + std::to_string(pixels.size()));
  vtkNew<vtkImageData> image;
  image->SetDimensions(width, height, 1);
  vtkNew<vtkUnsignedCharArray> scalars;
  scalars->SetNumberOfComponents(components);
  scalars->SetNumberOfTuples(static_cast<vtkIdType>(width) * height);
  std::copy(pixels.begin(), pixels.end(), scalars->GetPointer(0));
  image->GetPointData()->SetScalars(scalars);
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->WriteToMemoryOn();
  writer->Write();
  vtkUnsignedCharArray* bytes = writer->GetResult();
  if (!bytes) throw std::runtime_error("VTK could not encode a PNG");
  return std::string(reinterpret_cast<const char*>(bytes->GetPointer(0)),
                     static_cast<std::size_t>(bytes->GetNumberOfTuples()));
}

} // namespace phantasm
