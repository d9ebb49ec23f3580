// Writes the seed corpora of the NIfTI and mesh fuzz targets with phantasm's own writers (and
// VTK's and libnifti's for the formats phantasm only reads), so that no binary file is kept in the
// repository: small label volumes, an image, a displacement field (plain and gzip-compressed,
// NIfTI-1 and NIfTI-2) and a closed 20-triangle mesh in every mesh format, each mesh file behind
// the byte that makes fuzz_mesh read it as that format.
// Usage: fuzz_seeds NIFTI_FOLDER MESH_FOLDER
#include "geometry/triangle_mesh.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"

#include <nifti/nifti2_io.h>
#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPLYWriter.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkXMLPolyDataWriter.h>

#include <cstdint>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace phantasm;
namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Writes `bytes` behind the format byte fuzz_mesh reads (0 stl, 1 obj, 2 ply, 3 vtp).
void write_mesh_seed(const fs::path& path, int format, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.put(static_cast<char>(format));
  out << bytes;
}

/// A grid of `n` voxels per axis of 2 mm, rotated 90 degrees about z and shifted.
ImageGrid small_grid(int n) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i::Constant(n);
  grid.spacing_mm = Eigen::Vector3d::Constant(2.0);
  grid.world_from_voxel << 0, -2, 0, 10, 2, 0, 0, -5, 0, 0, 2, 3, 0, 0, 0, 1;
  return grid;
}

/// Labels `outer` in a ball and `inner` in a smaller one inside it, background at the edges.
std::vector<std::int32_t> nested_balls(int n, std::int32_t outer, std::int32_t inner) {
  std::vector<std::int32_t> labels;
  const double c = (n - 1) / 2.0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double r = std::sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
        labels.push_back(r < n / 6.0 ? inner : r < n / 2.0 - 1.0 ? outer : 0);
      }
  return labels;
}

void write_nifti_seeds(const fs::path& folder) {
  const ImageGrid grid = small_grid(8);
  write_nifti_labels(folder / "labels-uint8.nii", grid, nested_balls(8, 1, 2));
  write_nifti_labels(folder / "labels-uint8.nii.gz", grid, nested_balls(8, 3, 4));
  write_nifti_labels(folder / "labels-int16.nii", grid, nested_balls(8, 300, 2));
  std::vector<float> image;
  for (int v = 0; v < 6 * 5 * 4; ++v)
    image.push_back(0.5f * static_cast<float>(v % 7));
  ImageGrid image_grid = small_grid(1);
  image_grid.dims = Eigen::Vector3i(6, 5, 4);
  write_nifti(folder / "image-float.nii", image_grid, image);
  const ImageGrid field_grid = small_grid(3);
  std::vector<float> field(3 * 27);
  for (std::size_t v = 0; v < field.size(); ++v)
    field[v] = 0.25f * static_cast<float>(v % 5) - 0.5f;
  NiftiWriteOptions vectors;
  vectors.intent = NiftiIntent::displacement;
  vectors.components = 3;
  write_nifti(folder / "field.nii", field_grid, field, vectors);

  // NIfTI-2 (libnifti writes it; phantasm writes NIfTI-1 only), with a qform and no sform.
  const std::int64_t dims[8] = {3, 6, 6, 6, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
  const std::vector<std::int32_t> labels = nested_balls(6, 5, 6);
  for (std::size_t v = 0; v < labels.size(); ++v)
    static_cast<std::int16_t*>(nim->data)[v] = static_cast<std::int16_t>(labels[v]);
  nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->quatern_b = 0.0;
  nim->quatern_c = 0.0;
  nim->quatern_d = 1.0; // 180 degrees about z
  nim->qoffset_x = 4.0;
  nim->dx = nim->dy = nim->dz = 1.5;
  nim->pixdim[1] = nim->pixdim[2] = nim->pixdim[3] = 1.5;
  nim->qfac = 1.0;
  nim->nifti_type = NIFTI_FTYPE_NIFTI2_1;
  const std::string name = (folder / "labels-nifti2.nii").string();
  if (nifti_set_filenames(nim, name.c_str(), 0, 1) != 0) throw std::runtime_error("nifti_set_filenames");
  nifti_image_write(nim);
  nifti_image_free(nim);
}

void write_mesh_seeds(const fs::path& folder) {
  TriangleMesh mesh = unit_icosphere(0);
  mesh.vertices *= 10.0;
  vtkNew<vtkPoints> points;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    points->InsertNextPoint(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  vtkNew<vtkCellArray> triangles;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const vtkIdType ids[3] = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
    triangles->InsertNextCell(3, ids);
  }
  vtkNew<vtkPolyData> data;
  data->SetPoints(points);
  data->SetPolys(triangles);
  // Each writer writes a scratch file of its own extension (vtkPLYWriter adds ".ply" otherwise).
  const auto scratch = [&folder](const char* extension) {
    return folder / (std::string("scratch") + extension);
  };
  for (const bool binary : {false, true}) {
    vtkNew<vtkSTLWriter> stl;
    stl->SetInputData(data);
    stl->SetFileName(scratch(".stl").c_str());
    binary ? stl->SetFileTypeToBinary() : stl->SetFileTypeToASCII();
    stl->Write();
    write_mesh_seed(folder / (binary ? "binary.stl" : "ascii.stl"), 0, read_bytes(scratch(".stl")));
    vtkNew<vtkPLYWriter> ply;
    ply->SetInputData(data);
    ply->SetFileName(scratch(".ply").c_str());
    binary ? ply->SetFileTypeToBinary() : ply->SetFileTypeToASCII();
    ply->Write();
    write_mesh_seed(folder / (binary ? "binary.ply" : "ascii.ply"), 2, read_bytes(scratch(".ply")));
    vtkNew<vtkXMLPolyDataWriter> vtp;
    vtp->SetInputData(data);
    vtp->SetFileName(scratch(".vtp").c_str());
    binary ? vtp->SetDataModeToBinary() : vtp->SetDataModeToAscii();
    vtp->Write();
    write_mesh_seed(folder / (binary ? "binary.vtp" : "ascii.vtp"), 3, read_bytes(scratch(".vtp")));
  }
  // OBJ by hand: vertices, a normal, faces with and without texture and normal indices, a quad.
  std::ostringstream obj;
  obj << "# icosahedron\no organ\n";
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    obj << "v " << mesh.vertices(v, 0) << ' ' << mesh.vertices(v, 1) << ' ' << mesh.vertices(v, 2) << '\n';
  obj << "vn 0 0 1\nvt 0 0\n";
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    if (f % 2 == 0)
      obj << "f " << mesh.faces(f, 0) + 1 << ' ' << mesh.faces(f, 1) + 1 << ' ' << mesh.faces(f, 2) + 1
          << '\n';
    else
      obj << "f " << mesh.faces(f, 0) + 1 << "/1/1 " << mesh.faces(f, 1) + 1 << "/1/1 "
          << mesh.faces(f, 2) + 1 << "/1/1\n";
  }
  write_mesh_seed(folder / "icosahedron.obj", 1, obj.str());
  write_mesh_seed(folder / "square.obj", 1, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  // phantasm's own .vtp (appended, zlib-compressed, with field data).
  write_vtp(scratch(".vtp"), mesh);
  write_mesh_seed(folder / "phantasm.vtp", 3, read_bytes(scratch(".vtp")));
  for (const char* extension : {".stl", ".ply", ".vtp"})
    fs::remove(scratch(extension));
}

} // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: fuzz_seeds NIFTI_FOLDER MESH_FOLDER\n";
    return 2;
  }
  fs::create_directories(argv[1]);
  fs::create_directories(argv[2]);
  write_nifti_seeds(argv[1]);
  write_mesh_seeds(argv[2]);
  return 0;
}
