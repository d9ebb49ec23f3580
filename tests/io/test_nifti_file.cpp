#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "io/nifti_file.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <thread>

using namespace phantasm;
using phantasm::testing::fresh_folder;
using phantasm::testing::input_error_message;
namespace fs = std::filesystem;

namespace {

/// A rotated, anisotropic grid with an offset: every part of the affine is exercised.
ImageGrid oblique_grid() {
  ImageGrid grid;
  grid.dims = {5, 4, 3};
  grid.spacing_mm = {1.5, 2.0, 2.5};
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  grid.world_from_voxel.topLeftCorner<3, 3>() = rotation * grid.spacing_mm.asDiagonal();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-10, 20.5, 7);
  return grid;
}

/// Runs a Python script (Debian's interpreter, numpy and nibabel) written to folder/name with
/// `argument`; what it prints (its last line "ok" when its checks held) and its errors.
phantasm::testing::CommandResult run_script(const fs::path& folder, const std::string& name,
                                            const std::string& script, const std::string& argument) {
  phantasm::testing::write_text_file(folder / name, script);
  return phantasm::testing::run_command({PHANTASM_PYTHON, (folder / name).string(), argument});
}

} // namespace

TEST(NiftiFile, FloatImageRoundTripKeepsValuesAndAffine) {
  const fs::path folder = fresh_folder("nifti-float");
  const ImageGrid grid = oblique_grid();
  std::vector<float> values(static_cast<std::size_t>(grid.voxel_count()));
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = 0.5f * static_cast<float>(i) - 3.0f;
  for (const char* name : {"image.nii.gz", "image.nii"}) {
    write_nifti(folder / name, grid, values);
    const NiftiVolume back = read_nifti(folder / name);
    EXPECT_EQ(back.grid.dims, grid.dims);
    EXPECT_TRUE(back.grid.spacing_mm.isApprox(grid.spacing_mm, 1e-6));
    EXPECT_TRUE(back.grid.world_from_voxel.isApprox(grid.world_from_voxel, 1e-6))
        << back.grid.world_from_voxel;
    ASSERT_EQ(back.values.size(), values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
      ASSERT_EQ(back.values[i], static_cast<double>(values[i]));
  }
  // Identical input, identical bytes (no time stamp in the gzip stream).
  const std::string first = phantasm::testing::read_file(folder / "image.nii.gz");
  write_nifti(folder / "image.nii.gz", grid, values);
  EXPECT_EQ(phantasm::testing::read_file(folder / "image.nii.gz"), first);
  EXPECT_THROW(write_nifti(folder / "short.nii.gz", grid, {1.0f}), std::invalid_argument);
}

TEST(NiftiFile, LabelsUseTheNarrowestIntegerType) {
  const fs::path folder = fresh_folder("nifti-labels");
  const ImageGrid grid = oblique_grid();
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  labels[7] = 3;
  write_nifti_labels(folder / "small.nii.gz", grid, labels);
  ImageGrid back_grid;
  EXPECT_EQ(read_nifti_labels(folder / "small.nii.gz", &back_grid), labels);
  EXPECT_EQ(read_nifti(folder / "small.nii.gz").datatype, 2); // uint8
  labels[8] = 40000;
  write_nifti_labels(folder / "large.nii.gz", grid, labels);
  EXPECT_EQ(read_nifti(folder / "large.nii.gz").datatype, 8); // int32
  EXPECT_EQ(read_nifti_labels(folder / "large.nii.gz", nullptr), labels);
}

TEST(NiftiFile, BadFilesGetMessagesNamingFileAndProblem) {
  const fs::path folder = fresh_folder("nifti-bad");
  EXPECT_EQ(input_error_message([&] { read_nifti(folder / "none.nii.gz"); }),
            (folder / "none.nii.gz").string() + ": expected a NIfTI file, found no such file");
  phantasm::testing::write_text_file(folder / "text.nii", "not a nifti file at all");
  EXPECT_NE(input_error_message([&] { read_nifti(folder / "text.nii"); }).find("libnifti cannot read"),
            std::string::npos);

  ImageGrid grid = oblique_grid();
  const std::vector<float> field(static_cast<std::size_t>(grid.voxel_count()) * 3, 1.0f);
  write_nifti(folder / "field.nii.gz", grid, field, {NiftiIntent::displacement, 3, "field"});
  EXPECT_NE(input_error_message([&] {
              read_nifti(folder / "field.nii.gz");
            }).find("expected a 3-D volume, found dimension 5 of size 3"),
            std::string::npos);

  std::vector<float> fractional(static_cast<std::size_t>(grid.voxel_count()), 1.0f);
  fractional[0 + 5 * 2] = 0.5f; // voxel (0, 2, 0): i + nx j
  write_nifti(folder / "fraction.nii.gz", grid, fractional);
  EXPECT_NE(input_error_message([&] {
              read_nifti_labels(folder / "fraction.nii.gz", nullptr);
            }).find("expected whole-number labels, found 0.5"),
            std::string::npos);
  EXPECT_NE(input_error_message([&] {
              read_nifti_labels(folder / "fraction.nii.gz", nullptr);
            }).find("at voxel (0, 2, 0)"),
            std::string::npos);

  grid.world_from_voxel(0, 1) += 0.5; // shear: the sform can hold it, phantasm grids cannot
  write_nifti(folder / "shear.nii.gz", grid, fractional);
  EXPECT_NE(input_error_message([&] { read_nifti(folder / "shear.nii.gz"); }).find("without shear"),
            std::string::npos);
}

// nibabel, the reader most users load our images with, sees the affine, shape, datatype and
// intent docs/architecture.md specifies.
// A gzip stream damaged in the middle: zlib's error came back from znzread as (size_t)-1, taken
// for a read of that many bytes: the values past the voxels were scanned for NaN and the file was
// reported as "found NaN at value 139792 of 139776" (or worse).
TEST(NiftiFile, DamagedCompressedVoxelsAreNamedAsSuch) {
  const fs::path folder = fresh_folder("nifti-damaged");
  ImageGrid grid;
  grid.dims = {40, 40, 40};
  std::vector<float> values(static_cast<std::size_t>(grid.voxel_count()));
  for (std::size_t v = 0; v < values.size(); ++v)
    values[v] = static_cast<float>(std::sin(0.37 * static_cast<double>(v)));
  write_nifti(folder / "image.nii.gz", grid, values);
  std::string bytes = phantasm::testing::read_file(folder / "image.nii.gz");
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0xff);
  phantasm::testing::write_text_file(folder / "image.nii.gz", bytes);
  const std::string message = input_error_message([&] { read_nifti(folder / "image.nii.gz"); });
  EXPECT_EQ(message.rfind((folder / "image.nii.gz").string() +
                              ": expected gzip-compressed voxels zlib can inflate, found damaged compressed "
                              "data after ",
                          0),
            0u)
      << message;
}

TEST(NiftiFile, NibabelReadsAffineShapeDatatypeAndIntent) {
  const fs::path folder = fresh_folder("nifti-nibabel");
  const ImageGrid grid = oblique_grid();
  const std::vector<float> image(static_cast<std::size_t>(grid.voxel_count()), 2.5f);
  std::vector<float> field(static_cast<std::size_t>(grid.voxel_count()) * 3);
  for (std::size_t i = 0; i < field.size(); ++i)
    field[i] = static_cast<float>(i / static_cast<std::size_t>(grid.voxel_count())); // component index
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 2);
  write_nifti(folder / "image.nii.gz", grid, image);
  write_nifti(folder / "field.nii.gz", grid, field, {NiftiIntent::displacement, 3, ""});
  write_nifti_labels(folder / "labels.nii.gz", grid, labels);

  std::ostringstream expected_affine;
  expected_affine.precision(17);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      expected_affine << (r || c ? "," : "") << grid.world_from_voxel(r, c);
  const std::string script = R"(
import sys, numpy as np, nibabel as nib
folder, expected = sys.argv[1], np.array([float(v) for v in sys.argv[2].split(',')]).reshape(4, 4)
def check(name, shape, dtype, intent):
    img = nib.load(folder + '/' + name)
    h = img.header
    assert img.shape == shape, (name, img.shape)
    assert img.get_data_dtype() == np.dtype(dtype), (name, img.get_data_dtype())
    assert h.get_intent()[0] == intent, (name, h.get_intent())
    assert int(h['qform_code']) == 1 and int(h['sform_code']) == 1, name
    assert np.allclose(img.affine, expected, atol=1e-4), (name, img.affine)
    assert np.allclose(h.get_qform(), expected, atol=1e-4), (name, h.get_qform())
    assert h.get_xyzt_units() == ('mm', 'sec'), h.get_xyzt_units()
    return np.asanyarray(img.dataobj)
check('image.nii.gz', (5, 4, 3), 'float32', 'none')
f = check('field.nii.gz', (5, 4, 3, 1, 3), 'float32', 'vector')
assert all((f[..., 0, c] == c).all() for c in range(3))
check('labels.nii.gz', (5, 4, 3), 'uint8', 'label')
print('ok')
)";
  phantasm::testing::write_text_file(folder / "check.py", script);
  const auto result = phantasm::testing::run_command(
      {PHANTASM_PYTHON, (folder / "check.py").string(), folder.string(), expected_affine.str()});
  EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
  EXPECT_EQ(result.out, "ok\n") << result.err;
}

// A displacement field of 29 MB: the gzip file is two members (16 MiB of input, then the rest),
// read back value for value by libnifti, by nibabel and by Python's gzip as one stream, and
// byte-identical when written again, also by two threads at once (as the dataset writer does).
TEST(NiftiFile, ALargeCompressedFieldIsReadValueForValueAcrossItsGzipMembers) {
  const fs::path folder = fresh_folder("nifti-large-gzip");
  ImageGrid grid;
  grid.dims = {160, 150, 100};
  grid.spacing_mm = {1.0, 1.0, 1.0};
  const std::size_t voxels = static_cast<std::size_t>(grid.voxel_count());
  std::vector<float> field(3 * voxels);
  for (std::size_t c = 0, n = 0; c < 3; ++c)
    for (std::size_t v = 0; v < voxels; ++v, ++n)
      field[n] = static_cast<float>(c) * 1000.0f + 0.25f * static_cast<float>(v % 977); // exact in float32
  const NiftiWriteOptions options{NiftiIntent::displacement, 3, "large"};
  const fs::path path = folder / "field.nii.gz";
  write_nifti(path, grid, field, options);
  const std::string first = phantasm::testing::read_file(path);
  write_nifti(path, grid, field, options);
  EXPECT_EQ(phantasm::testing::read_file(path), first);
  std::thread other([&] { write_nifti(folder / "other.nii.gz", grid, field, options); });
  write_nifti(folder / "this.nii.gz", grid, field, options);
  other.join();
  EXPECT_EQ(phantasm::testing::read_file(folder / "other.nii.gz"), first);
  EXPECT_EQ(phantasm::testing::read_file(folder / "this.nii.gz"), first);

  const NiftiVolume back = read_nifti_vectors(path);
  ASSERT_EQ(back.values.size(), field.size());
  std::size_t wrong = 0;
  for (std::size_t n = 0; n < field.size(); ++n)
    wrong += back.values[n] != static_cast<double>(field[n]);
  EXPECT_EQ(wrong, 0u);

  const std::string script = R"(
import sys, gzip, zlib, numpy as np, nibabel as nib
path = sys.argv[1]
raw = open(path, 'rb').read()
members, data = 0, b''
while raw:
    member = zlib.decompressobj(31)
    data += member.decompress(raw)
    assert member.eof, 'a member ends early'
    raw = member.unused_data
    members += 1
assert members == 2, members
assert len(data) == 352 + 160 * 150 * 100 * 3 * 4, len(data)
assert gzip.decompress(open(path, 'rb').read()) == data
img = nib.load(path)
f = np.asanyarray(img.dataobj)
assert f.shape == (160, 150, 100, 1, 3) and f.dtype == np.float32, (f.shape, f.dtype)
v = np.arange(160 * 150 * 100)
for c in range(3):
    expected = (c * 1000 + 0.25 * (v % 977)).astype(np.float32)
    assert (f[..., 0, c].reshape(-1, order='F') == expected).all(), c
print('ok')
)";
  const auto result = run_script(folder, "check.py", script, path.string());
  EXPECT_EQ(result.out, "ok\n") << result.err;
}

// Found by fuzz/fuzz_nifti.cpp: a vox_offset beyond 2^31 became a negative offset in libnifti,
// which then read an uncompressed file's voxels from its end or from byte 348 (and refused the file
// gzipped).
TEST(NiftiFile, AVoxelOffsetBeyond2To31IsRefused) {
  const fs::path folder = fresh_folder("nifti-offset");
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(4, 4, 4);
  write_nifti(folder / "image.nii", grid, std::vector<float>(64, 1.0f));
  std::string bytes;
  {
    std::ifstream in(folder / "image.nii", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const float offset = 1.5e16f;
  bytes.replace(108, 4, reinterpret_cast<const char*>(&offset), 4); // vox_offset
  phantasm::testing::write_text_file(folder / "far.nii", bytes);
  EXPECT_EQ(input_error_message([&] { read_nifti(folder / "far.nii"); }),
            (folder / "far.nii").string() +
                ": expected the voxels at a whole byte offset (vox_offset) below 2^31, found " +
                format_number(static_cast<double>(offset)));
}

// The voxels are read in pieces of 1 MiB: files of several pieces, big-endian (swapped piece by
// piece) and little-endian, gzipped and not, written by nibabel, read back value for value.
TEST(NiftiFile, LargeFilesOfEitherByteOrderAreReadValueForValue) {
  const fs::path folder = fresh_folder("nifti-pieces");
  const std::string script = R"(
import sys, numpy as np, nibabel as nib
folder = sys.argv[1]
shape = (96, 80, 70)  # 537600 voxels: 2.05 MiB of float32, 4.1 MiB of float64
i, j, k = np.indices(shape)
for name, dtype, order in [('be_f4.nii.gz', 'f4', '>'), ('be_f8.nii', 'f8', '>'), ('be_i2.nii.gz', 'i2', '>'),
                           ('le_f4.nii', 'f4', '<')]:
    values = (i + 1000 * j + 100000 * k) if dtype != 'i2' else (i + 97 * j - 11 * k)
    header = nib.Nifti1Header(endianness=order)
    header.set_data_dtype(np.dtype(order + dtype))
    nib.save(nib.Nifti1Image(values.astype(order + dtype), np.eye(4), header), folder + '/' + name)
print('ok')
)";
  const auto written = run_script(folder, "write.py", script, folder.string());
  ASSERT_EQ(written.out, "ok\n") << written.err;
  for (const std::string name : {"be_f4.nii.gz", "be_f8.nii", "be_i2.nii.gz", "le_f4.nii"}) {
    SCOPED_TRACE(name);
    const NiftiVolume volume = read_nifti(folder / name);
    ASSERT_EQ(volume.grid.dims, Eigen::Vector3i(96, 80, 70));
    const bool labels = name == "be_i2.nii.gz";
    std::size_t wrong = 0;
    for (int k = 0, n = 0; k < 70; ++k)
      for (int j = 0; j < 80; ++j)
        for (int i = 0; i < 96; ++i, ++n) {
          const double expected = labels ? i + 97 * j - 11 * k : i + 1000.0 * j + 100000.0 * k;
          wrong += volume.values[static_cast<std::size_t>(n)] != expected;
        }
    EXPECT_EQ(wrong, 0u);
  }
}

// Ctrl-C during a read stops it between two pieces (a large field takes seconds to decompress):
// the read raises Cancelled long before its last piece, and reads again once the request is gone.
TEST(NiftiFile, ACancellationStopsAReadBetweenTwoPieces) {
  const fs::path folder = fresh_folder("nifti-cancel");
  ImageGrid grid;
  grid.dims = {64, 64, 256}; // 4 MiB of float32: four pieces
  std::vector<float> values(static_cast<std::size_t>(grid.voxel_count()));
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = static_cast<float>(i % 1000);
  write_nifti(folder / "large.nii.gz", grid, values);
  set_read_delay_for_testing(400); // 1.6 s for the whole file
  std::thread stop([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    request_cancellation();
  });
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(read_nifti(folder / "large.nii.gz"), Cancelled);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stop.join();
  reset_cancellation();
  set_read_delay_for_testing(0);
  // Stopped at the first poll after the request: one or two pauses, not four.
  EXPECT_LT(seconds, 1.2);
  EXPECT_EQ(read_nifti(folder / "large.nii.gz").values[123456], 456.0);
}

// Gzipped voxels are inflated member by member with libdeflate (our writer's members of 16 MiB
// of input, nibabel's and gzip's one member, either byte order): the same values as zlib's
// stream gives them, and a damaged member leaves the file to zlib, which names the damage.
TEST(NiftiFile, WholeMembersAndZlibsStreamReadTheSameValues) {
  const fs::path folder = fresh_folder("nifti-members");
  ImageGrid grid;
  grid.dims = {128, 128, 100}; // 6.25 MiB of float32 a component: two members of ours
  const std::size_t voxels = static_cast<std::size_t>(grid.voxel_count());
  std::vector<float> field(3 * voxels);
  for (std::size_t n = 0; n < field.size(); ++n)
    field[n] = static_cast<float>(std::sin(0.001 * static_cast<double>(n)) * 40.0);
  write_nifti(folder / "ours.nii.gz", grid, field, {NiftiIntent::displacement, 3, "field"});
  const std::string script = R"(
import sys, numpy as np, nibabel as nib
folder = sys.argv[1]
i, j, k = np.indices((90, 70, 60))
for name, order in [('big.nii.gz', '>'), ('little.nii.gz', '<')]:
    header = nib.Nifti1Header(endianness=order)
    header.set_data_dtype(np.dtype(order + 'i2'))
    nib.save(nib.Nifti1Image((i + 97 * j - 11 * k).astype(order + 'i2'), np.eye(4), header), folder + '/' + name)
print('ok')
)";
  const auto written = run_script(folder, "write.py", script, folder.string());
  ASSERT_EQ(written.out, "ok\n") << written.err;
  // gzip's own member, of a file written uncompressed.
  write_nifti(folder / "plain.nii", grid, std::vector<float>(field.begin(), field.begin() + voxels));
  const auto gzipped = phantasm::testing::run_command({"/bin/gzip", "-k", (folder / "plain.nii").string()});
  ASSERT_TRUE(fs::exists(folder / "plain.nii.gz")) << gzipped.err;

  for (const std::string name : {"ours.nii.gz", "big.nii.gz", "little.nii.gz", "plain.nii.gz"}) {
    SCOPED_TRACE(name);
    const auto read = [&] {
      return name == "ours.nii.gz" ? read_nifti_vectors(folder / name) : read_nifti(folder / name);
    };
    const std::size_t before = whole_member_reads_for_testing();
    const NiftiVolume whole = read();
    EXPECT_EQ(whole_member_reads_for_testing(), before + 1); // not left to zlib
    set_whole_member_reads_for_testing(false);
    const NiftiVolume streamed = read();
    set_whole_member_reads_for_testing(true);
    EXPECT_EQ(whole_member_reads_for_testing(), before + 1);
    ASSERT_EQ(whole.values.size(), streamed.values.size());
    EXPECT_TRUE(whole.values == streamed.values);
    EXPECT_EQ(whole.grid.world_from_voxel, streamed.grid.world_from_voxel);
  }
  // A damaged second member: left to zlib, which names it.
  std::string bytes = phantasm::testing::read_file(folder / "ours.nii.gz");
  bytes[bytes.size() - 1000] = static_cast<char>(bytes[bytes.size() - 1000] ^ 0x55);
  phantasm::testing::write_text_file(folder / "damaged.nii.gz", bytes);
  const std::size_t before = whole_member_reads_for_testing();
  const std::string message = input_error_message([&] { read_nifti_vectors(folder / "damaged.nii.gz"); });
  EXPECT_EQ(whole_member_reads_for_testing(), before);
  EXPECT_NE(message.find("damaged compressed data"), std::string::npos) << message;
}

// Integer labels of up to 32 bits are taken as they are; scaled ones, and -2^31 (beyond int32's
// magnitude), go through the whole-number check; a datatype that is not a real scalar is named.
TEST(NiftiFile, IntegerLabelsOfEveryWidthAndScaling) {
  const fs::path folder = fresh_folder("nifti-label-types");
  const std::string script = R"(
import sys, numpy as np, nibabel as nib
folder = sys.argv[1]
i, j, k = np.indices((6, 5, 4))
values = i + 7 * j - 20 * k  # -60 .. 33
for name, dtype in [('u1', 'u1'), ('i1', 'i1'), ('i2', 'i2'), ('u2', 'u2'), ('i4', 'i4'), ('u4', 'u4'), ('f4', 'f4')]:
    v = values - values.min() if dtype[0] == 'u' else values
    nib.save(nib.Nifti1Image(v.astype(dtype), np.eye(4)), folder + '/' + name + '.nii.gz')
scaled = nib.Nifti1Image(values.astype('i2'), np.eye(4))
scaled.header.set_slope_inter(2.0, 1.0)
nib.save(scaled, folder + '/scaled.nii.gz')
lowest = values.astype('i4')
lowest[1, 2, 3] = -2**31
nib.save(nib.Nifti1Image(lowest, np.eye(4)), folder + '/lowest.nii.gz')
nib.save(nib.Nifti1Image(values.astype('c8'), np.eye(4)), folder + '/complex.nii.gz')
print('ok')
)";
  const auto written = run_script(folder, "write.py", script, folder.string());
  ASSERT_EQ(written.out, "ok\n") << written.err;
  const auto expected = [](int i, int j, int k, bool shifted) {
    return i + 7 * j - 20 * k + (shifted ? 60 : 0);
  };
  for (const std::string name : {"u1", "i1", "i2", "u2", "i4", "u4", "f4", "scaled"}) {
    SCOPED_TRACE(name);
    const std::vector<std::int32_t> labels = read_nifti_labels(folder / (name + ".nii.gz"), nullptr);
    ASSERT_EQ(labels.size(), 120u);
    std::size_t wrong = 0;
    for (int k = 0, n = 0; k < 4; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i, ++n) {
          const int value = expected(i, j, k, name[0] == 'u');
          wrong += labels[static_cast<std::size_t>(n)] != (name == "scaled" ? 2 * value + 1 : value);
        }
    EXPECT_EQ(wrong, 0u);
  }
  EXPECT_NE(input_error_message([&] {
              read_nifti_labels(folder / "lowest.nii.gz", nullptr);
            }).find("expected whole-number labels, found -2147483648.000000 at voxel (1, 2, 3)"),
            std::string::npos);
  // Not a real scalar type: named, labels or not.
  for (const bool labels : {false, true}) {
    const std::string message = input_error_message([&] {
      if (labels) {
        read_nifti_labels(folder / "complex.nii.gz", nullptr);
      } else {
        read_nifti(folder / "complex.nii.gz");
      }
    });
    EXPECT_NE(message.find("expected a real scalar datatype, found NIfTI datatype 32"), std::string::npos)
        << message;
  }
}
