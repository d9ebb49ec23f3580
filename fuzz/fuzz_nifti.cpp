// libFuzzer target: NIfTI files as phantasm reads them: label volumes of scene organs
// (read_shape_files: labels, affine and extent checks, label boxes), and the images, masks and
// displacement fields `phantasm eval` reads (read_nifti, read_nifti_vectors). The input is the
// file's bytes: read as .nii.gz when it starts with gzip's magic number, else as .nii and then
// again gzip-compressed as .nii.gz, where the reader must answer the same. Only InputError may
// refuse a file.
#include "fuzz/fuzz_support.hpp"
#include "io/nifti_file.hpp"
#include "io/shape_files.hpp"

#include <zlib.h>

#include <cstdint>
#include <string>
#include <vector>

using namespace phantasm;

namespace {

/// What the readers made of a file: each reader's message ("" when it read the file) and a
/// summary of what it read.
std::string outcome(const std::filesystem::path& path) {
  std::string answer;
  const auto run = [&](const char* name, auto&& read) {
    answer += name;
    answer += ": ";
    fuzz::expect_input_errors_only(name, [&] {
      try {
        answer += read();
      } catch (const InputError& error) {
        // Messages name the file: compare them without its name.
        std::string message = error.what();
        for (std::size_t at; (at = message.find(path.string())) != std::string::npos;)
          message.replace(at, path.string().size(), "FILE");
        answer += "refused: " + message;
      }
    });
    answer += "\n";
  };
  run("read_nifti", [&] {
    const NiftiVolume volume = read_nifti(path);
    return std::to_string(volume.values.size()) + " values";
  });
  run("read_nifti_vectors", [&] {
    const NiftiVolume volume = read_nifti_vectors(path, 3);
    return std::to_string(volume.values.size()) + " values";
  });
  run("read_shape_files", [&] {
    // An organ of the file's first non-zero label (label 1 when it has none), with an organ of
    // another label nested in it when there is one, on a scene grid of 1 mm voxels about the origin.
    ImageGrid grid;
    const std::vector<std::int32_t> labels = read_nifti_labels(path, &grid);
    std::vector<std::int32_t> found;
    for (const std::int32_t label : labels)
      if (label != 0 && (found.empty() || (found.size() == 1 && label != found[0]))) found.push_back(label);
    if (found.empty()) found.push_back(1);
    AnatomySettings anatomy;
    for (std::size_t i = 0; i < found.size(); ++i) {
      OrganSettings organ;
      organ.name = "organ" + std::to_string(i);
      organ.inside = i == 0 ? "" : "organ0";
      organ.shape.kind = ShapeKind::label_volume;
      organ.shape.file = path;
      organ.shape.label = found[i];
      organ.shape.labels = {std::to_string(found[i])};
      anatomy.organs.push_back(organ);
    }
    const ImageGrid scene_grid = make_centered_grid(Eigen::Vector3d::Constant(200.0), Eigen::Vector3d::Ones(),
                                                    Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
    const auto files = read_shape_files(anatomy, {}, scene_grid);
    return std::to_string(files.size()) + " organs";
  });
  return answer;
}

/// The bytes gzip-compressed (gzip header, as .nii.gz files are).
std::vector<std::uint8_t> gzip(const std::uint8_t* data, std::size_t size) {
  z_stream stream{};
  if (deflateInit2(&stream, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    fuzz::finding("deflateInit2");
  std::vector<std::uint8_t> out(deflateBound(&stream, size) + 32);
  stream.next_in = const_cast<std::uint8_t*>(data);
  stream.avail_in = static_cast<uInt>(size);
  stream.next_out = out.data();
  stream.avail_out = static_cast<uInt>(out.size());
  if (deflate(&stream, Z_FINISH) != Z_STREAM_END) fuzz::finding("deflate");
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size >= 2 && data[0] == 0x1f && data[1] == 0x8b) {
    (void)outcome(fuzz::write_scratch_file("volume.nii.gz", data, size));
    return 0;
  }
  const std::string plain = outcome(fuzz::write_scratch_file("volume.nii", data, size));
  const std::vector<std::uint8_t> compressed = gzip(data, size);
  const std::string gz =
      outcome(fuzz::write_scratch_file("volume.nii.gz", compressed.data(), compressed.size()));
  if (plain != gz)
    fuzz::finding("the file read differently plain and gzip-compressed:\n.nii:\n" + plain + ".nii.gz:\n" +
                  gz);
  return 0;
}
