// NIfTI-1 writing (our own header and gzip by libdeflate, so writes are atomic and byte-identical) and
// NIfTI-1/2 reading through libnifti2.

#include "io/nifti_file.hpp"

#include "core/abandonable_work.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/path_kind.hpp"
#include "io/atomic_file.hpp"
#include "io/file_error.hpp"

#include <libdeflate.h>
#include <nifti/nifti2_io.h>

#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <type_traits>
#include <vector>

namespace phantasm {
namespace {

std::atomic<int> g_read_delay_ms{0};
std::atomic<std::size_t> g_whole_member_reads{0};
std::atomic<bool> g_whole_member_reads_enabled{true};

bool ends_with_gz(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  return name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0;
}

/// The 348-byte NIfTI-1 header of a grid, with the qform and sform both set to world_from_voxel.
nifti_1_header make_header(const ImageGrid& grid, int components, int datatype, int bits,
                           const NiftiWriteOptions& options) {
  nifti_1_header h;
  std::memset(&h, 0, sizeof h);
  h.sizeof_hdr = 348;
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] < 1 || grid.dims[a] > std::numeric_limits<std::int16_t>::max()) {
      throw std::invalid_argument("NIfTI-1: grid dimension " + std::to_string(grid.dims[a]) +
                                  " outside [1, 32767]");
    }
  }
  const bool fourth = components > 1 && options.components_in_fourth_dimension;
  h.dim[0] = static_cast<short>(components > 1 ? (fourth ? 4 : 5) : 3);
  h.dim[1] = static_cast<short>(grid.dims.x());
  h.dim[2] = static_cast<short>(grid.dims.y());
  h.dim[3] = static_cast<short>(grid.dims.z());
  h.dim[4] = static_cast<short>(fourth ? components : 1);
  h.dim[5] = static_cast<short>(fourth ? 1 : components);
  h.dim[6] = h.dim[7] = 1;
  h.intent_code = static_cast<short>(options.intent);
  h.datatype = static_cast<short>(datatype);
  h.bitpix = static_cast<short>(bits);
  h.pixdim[1] = static_cast<float>(grid.spacing_mm.x());
  h.pixdim[2] = static_cast<float>(grid.spacing_mm.y());
  h.pixdim[3] = static_cast<float>(grid.spacing_mm.z());
  h.pixdim[4] = 1.0f;
  h.vox_offset = 352.0f;
  h.scl_slope = 1.0f;
  h.xyzt_units = NIFTI_UNITS_MM | NIFTI_UNITS_SEC;
  std::strncpy(h.descrip, options.description.c_str(), sizeof h.descrip - 1);
  h.qform_code = NIFTI_XFORM_SCANNER_ANAT;
  h.sform_code = NIFTI_XFORM_SCANNER_ANAT;

  nifti_dmat44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      m.m[r][c] = grid.world_from_voxel(r, c);
  double qb, qc, qd, qx, qy, qz, dx, dy, dz, qfac;
  nifti_dmat44_to_quatern(m, &qb, &qc, &qd, &qx, &qy, &qz, &dx, &dy, &dz, &qfac);
  h.quatern_b = static_cast<float>(qb);
  h.quatern_c = static_cast<float>(qc);
  h.quatern_d = static_cast<float>(qd);
  h.qoffset_x = static_cast<float>(qx);
  h.qoffset_y = static_cast<float>(qy);
  h.qoffset_z = static_cast<float>(qz);
  h.pixdim[0] = static_cast<float>(qfac);
  for (int c = 0; c < 4; ++c) {
    h.srow_x[c] = static_cast<float>(grid.world_from_voxel(0, c));
    h.srow_y[c] = static_cast<float>(grid.world_from_voxel(1, c));
    h.srow_z[c] = static_cast<float>(grid.world_from_voxel(2, c));
  }
  std::memcpy(h.magic, "n+1\0", 4);
  return h;
}

/// Streams bytes to an atomic file, gzip-compressed or as they are. The gzip file is a series of
/// members (RFC 1952, section 2.2) of up to 16 MiB of input each, compressed by libdeflate at level
/// 1 in one call per member (mtime 0, so identical input gives identical bytes): these volumes are
/// large and smooth, and speed matters more than the last 10 %. libdeflate compresses them 2 to 3
/// times as fast as zlib's level 1, and a little smaller; members bound the memory it needs, and
/// every gzip reader (zlib's gzread, Python's gzip, hence libnifti, ITK and nibabel) reads them
/// as one stream.
class NiftiStream {
public:
  static constexpr std::size_t k_member_bytes = std::size_t{1} << 24;

  explicit NiftiStream(const std::filesystem::path& path)
      : m_file(path), m_gzip(ends_with_gz(path)),
        m_compressor(m_gzip ? libdeflate_alloc_compressor(1) : nullptr, free_compressor) {
    if (m_gzip && !m_compressor) throw std::runtime_error("libdeflate: cannot allocate a compressor");
  }
  NiftiStream(const NiftiStream&) = delete;
  NiftiStream& operator=(const NiftiStream&) = delete;

  void write(const void* data, std::size_t size) {
    if (!m_gzip) {
      m_file.write(data, size);
      return;
    }
    const auto* bytes = static_cast<const unsigned char*>(data);
    while (size > 0) {
      if (m_pending.empty() && size >= k_member_bytes) { // a whole member straight from the caller
        write_member(bytes, k_member_bytes);
        bytes += k_member_bytes;
        size -= k_member_bytes;
        continue;
      }
      const std::size_t part = std::min(size, k_member_bytes - m_pending.size());
      m_pending.insert(m_pending.end(), bytes, bytes + part);
      bytes += part;
      size -= part;
      if (m_pending.size() == k_member_bytes) flush_pending();
    }
  }
  void commit() {
    if (m_gzip && (!m_pending.empty() || !m_wrote_member)) flush_pending();
    m_file.commit();
  }

private:
  static void free_compressor(libdeflate_compressor* compressor) {
    if (compressor != nullptr) libdeflate_free_compressor(compressor);
  }
  void flush_pending() {
    write_member(m_pending.data(), m_pending.size());
    m_pending.clear();
  }
  void write_member(const unsigned char* bytes, std::size_t size) {
    throw_if_cancelled();
    m_compressed.resize(libdeflate_gzip_compress_bound(m_compressor.get(), size));
    std::size_t compressed = 0;
    {
      // One call that polls nothing (about 0.1 s), into memory: a cancelled run may be
      // abandoned inside it.
      const AbandonableWork compressing;
      compressed =
          libdeflate_gzip_compress(m_compressor.get(), bytes, size, m_compressed.data(), m_compressed.size());
    }
    if (compressed == 0) throw std::runtime_error("libdeflate: gzip compression failed");
    m_file.write(m_compressed.data(), compressed);
    m_wrote_member = true;
  }

  AtomicFileWriter m_file;
  bool m_gzip;
  std::unique_ptr<libdeflate_compressor, void (*)(libdeflate_compressor*)> m_compressor;
  std::vector<unsigned char> m_pending, m_compressed;
  bool m_wrote_member = false;
};

template <typename T>
void write_volume(const std::filesystem::path& path, const ImageGrid& grid, const T* values,
                  std::size_t count, int datatype, const NiftiWriteOptions& options) {
  const std::size_t expected =
      static_cast<std::size_t>(grid.voxel_count()) * static_cast<std::size_t>(options.components);
  if (count != expected) {
    throw std::invalid_argument("NIfTI " + path.string() + ": expected " + std::to_string(expected) +
                                " values, found " + std::to_string(count));
  }
  const nifti_1_header header = make_header(grid, options.components, datatype, 8 * sizeof(T), options);
  NiftiStream stream(path);
  stream.write(&header, sizeof header);
  const char extension[4] = {0, 0, 0, 0};
  stream.write(extension, sizeof extension);
  stream.write(values, count * sizeof(T));
  stream.commit();
}

} // namespace

void write_nifti(const std::filesystem::path& path, const ImageGrid& grid, const std::vector<float>& values,
                 const NiftiWriteOptions& options) {
  write_volume(path, grid, values.data(), values.size(), DT_FLOAT32, options);
}

void write_nifti_whole_numbers(const std::filesystem::path& path, const ImageGrid& grid,
                               const std::vector<float>& values, bool is_signed,
                               const NiftiWriteOptions& options) {
  const auto narrow = [&values](auto type) {
    using T = decltype(type);
    const double low = std::numeric_limits<T>::min(), high = std::numeric_limits<T>::max();
    std::vector<T> out(values.size());
    for (std::size_t v = 0; v < values.size(); ++v) {
      const double value = std::isfinite(values[v]) ? std::round(double{values[v]}) : 0.0;
      out[v] = static_cast<T>(std::clamp(value, low, high));
    }
    return out;
  };
  if (is_signed) {
    const std::vector<std::int16_t> out = narrow(std::int16_t{});
    write_volume(path, grid, out.data(), out.size(), DT_INT16, options);
  } else {
    const std::vector<std::uint16_t> out = narrow(std::uint16_t{});
    write_volume(path, grid, out.data(), out.size(), DT_UINT16, options);
  }
}

void write_nifti_labels(const std::filesystem::path& path, const ImageGrid& grid,
                        const std::vector<std::int32_t>& labels, const NiftiWriteOptions& options) {
  NiftiWriteOptions o = options;
  if (o.intent == NiftiIntent::none) o.intent = NiftiIntent::label;
  std::int32_t low = 0, high = 0;
  if (!labels.empty()) {
    const auto [min, max] = std::minmax_element(labels.begin(), labels.end());
    low = *min;
    high = *max;
  }
  if (low >= 0 && high <= 255) {
    const std::vector<std::uint8_t> narrow(labels.begin(), labels.end());
    write_volume(path, grid, narrow.data(), narrow.size(), DT_UINT8, o);
  } else if (low >= std::numeric_limits<std::int16_t>::min() &&
             high <= std::numeric_limits<std::int16_t>::max()) {
    const std::vector<std::int16_t> narrow(labels.begin(), labels.end());
    write_volume(path, grid, narrow.data(), narrow.size(), DT_INT16, o);
  } else {
    write_volume(path, grid, labels.data(), labels.size(), DT_INT32, o);
  }
}

namespace {

/// Refuses a vox_offset (the byte where the voxels start, as the header gives it) that is not a
/// whole number below 2^31. libnifti converts NIfTI-1's float offset to an int: beyond its range
/// the offset became negative, and libnifti then read an uncompressed file's voxels from the end
/// of the file, or the header bytes after replacing it by 348, and refused the file gzipped.
void check_voxel_offset(const std::filesystem::path& path) {
  const znzFile file = znzopen(path.c_str(), "rb", nifti_is_gzfile(path.c_str()));
  if (znz_isnull(file)) return; // libnifti says what is wrong
  znzFile handle = file;
  unsigned char header[348] = {};
  const std::size_t read = znzread(header, 1, sizeof header, handle);
  znzclose(handle);
  if (read < sizeof header) return;
  const auto swapped = [](unsigned char* at, std::size_t size, bool swap) {
    if (swap) std::reverse(at, at + size);
    return at;
  };
  std::int32_t size = 0;
  std::memcpy(&size, header, 4);
  const bool swap = size != 348 && size != 540;
  std::memcpy(&size, swapped(header, 4, swap), 4);
  // The magic tells NIfTI from ANALYZE 7.5, whose header has the same size: libnifti reads a
  // .nii file without it as NIfTI-1 anyway, taking the voxels from vox_offset (often 0, the header).
  const bool nifti1 = std::memcmp(header + 344, "n+1", 4) == 0 || std::memcmp(header + 344, "ni1", 4) == 0;
  const bool nifti2 = std::memcmp(header + 4, "n+2", 4) == 0 || std::memcmp(header + 4, "ni2", 4) == 0;
  if ((size == 348 && !nifti1) || (size == 540 && !nifti2))
    throw_file_error(path,
                     "expected a NIfTI-1 or NIfTI-2 header (magic \"n+1\" or \"n+2\"), found a header of " +
                         std::to_string(size) + " bytes without it (ANALYZE 7.5?)");
  double offset = 0.0;
  if (size == 348) {
    float value = 0.0f;
    std::memcpy(&value, swapped(header + 108, 4, swap), 4);
    offset = value;
  } else if (size == 540) {
    std::int64_t value = 0;
    std::memcpy(&value, swapped(header + 168, 8, swap), 8);
    offset = static_cast<double>(value);
  } else {
    return; // not a NIfTI header: libnifti refuses it
  }
  if (!(offset >= 0.0) || offset >= 2147483648.0 || offset != std::floor(offset))
    throw_file_error(path, "expected the voxels at a whole byte offset (vox_offset) below 2^31, found " +
                               format_number(offset));
}

/// The voxel bytes [offset, offset + needed) of a gzipped file, inflated by libdeflate member by
/// member (our writer's files are members of up to 16 MiB of input each, other writers' one
/// member): whole buffers at a time, faster than zlib's stream through libnifti (a 120 MB field
/// read in 0.58 s against 0.71 s, bench_scene_io), which reading a subject's volumes back for its
/// page, a pair's fields and an evaluation's images spend much of their time in. Polls the cancellation flag
/// between members. Returns nothing when the file is not one this path takes (a member that does not inflate
/// or would not fit, too few bytes, more than 1 GiB of voxels, which one call could take seconds over): the
/// caller then reads it through zlib, which names what is wrong.
std::optional<std::vector<unsigned char>> inflate_voxels(const char* file, std::uint64_t offset,
                                                         std::uint64_t needed) {
  constexpr std::uint64_t k_largest = std::uint64_t{1} << 30;
  if (needed > k_largest || offset > k_largest) return std::nullopt;
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(file, error);
  // Deflate makes at most 1032 bytes of a byte: a header claiming more voxels than that is short,
  // and is not given a buffer of its claim.
  if (error || size > 2 * k_largest || offset + needed > 1032 * static_cast<std::uint64_t>(size))
    return std::nullopt;
  // Buffers left uninitialized: a claim of more voxels than the file holds costs address space,
  // not memory, and the bytes are written once.
  const auto in_size = static_cast<std::size_t>(size);
  const std::unique_ptr<unsigned char[]> compressed(new unsigned char[in_size]);
  {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> in(std::fopen(file, "rb"), std::fclose);
    if (!in || std::fread(compressed.get(), 1, in_size, in.get()) != in_size) return std::nullopt;
  }
  const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> decompressor(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  if (!decompressor) return std::nullopt;
  // The stream up to the voxels' end; the voxels are copied out once it is whole.
  const auto out_size = static_cast<std::size_t>(offset + needed);
  const std::unique_ptr<unsigned char[]> stream(new unsigned char[out_size]);
  std::size_t consumed = 0, produced = 0;
  while (produced < out_size) {
    throw_if_cancelled();
    if (consumed >= in_size) return std::nullopt; // too few bytes
    std::size_t in_bytes = 0, out_bytes = 0;
    const libdeflate_result result =
        libdeflate_gzip_decompress_ex(decompressor.get(), compressed.get() + consumed, in_size - consumed,
                                      stream.get() + produced, out_size - produced, &in_bytes, &out_bytes);
    if (result != LIBDEFLATE_SUCCESS || in_bytes == 0) return std::nullopt;
    consumed += in_bytes;
    produced += out_bytes;
  }
  return std::vector<unsigned char>(stream.get() + offset, stream.get() + out_size);
}

/// Reads the voxels a header describes, in pieces, and returns their bytes in this machine's
/// byte order. Checks first that their count is what the dimensions multiply to, and that an
/// uncompressed file holds their bytes (a header of a few hundred bytes can claim 10^12 voxels:
/// the buffer is allocated only after that, and grows as a gzipped file's bytes arrive, so a
/// short gzipped file is named as such, not as too large for memory). Refuses a float image with
/// a NaN or infinite value (libnifti would have set them to 0 as it loads, so a field of NaN
/// would read as no motion). Polls the cancellation flag between pieces of 1 MiB, or between
/// gzip members (inflate_voxels): decompressing a large field through zlib takes seconds, and
/// Ctrl-C must not wait for it.
std::vector<unsigned char> read_voxel_data(const std::filesystem::path& path, const nifti_image& header) {
  double product = 1.0;
  std::string dims;
  for (int d = 1; d <= std::clamp<int>(static_cast<int>(header.dim[0]), 0, 7); ++d) {
    product *= static_cast<double>(header.dim[d]);
    dims += (d > 1 ? " x " : "") + std::to_string(header.dim[d]);
  }
  // Whole numbers up to 2^53 are exact in a double; no file of this machine holds more voxels.
  if (!(product >= 1.0) || product > 9007199254740992.0 || static_cast<double>(header.nvox) != product ||
      header.nbyper <= 0)
    throw_file_error(
        path, "expected positive dimensions whose product is the voxel count, found dimensions " + dims);
  for (const std::int64_t n : {header.nx, header.ny, header.nz}) {
    if (n > std::numeric_limits<int>::max())
      throw_file_error(path, "expected at most 2^31 - 1 voxels along an axis, found dimensions " + dims);
  }
  const std::uint64_t needed =
      static_cast<std::uint64_t>(header.nvox) * static_cast<std::uint64_t>(header.nbyper);
  const auto short_file = [&](std::uint64_t found) {
    throw_file_error(path, "expected " + std::to_string(needed) + " bytes of voxels (dimensions " + dims +
                               ", " + std::to_string(header.nbyper) + " bytes each) from byte " +
                               std::to_string(header.iname_offset) + ", found " + std::to_string(found));
  };
  const bool gzip = nifti_is_gzfile(header.iname) != 0;
  if (!gzip) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(header.iname, error);
    const auto offset = static_cast<std::uint64_t>(header.iname_offset);
    if (!error && size < offset + needed) short_file(size > offset ? size - offset : 0);
  }
  std::vector<unsigned char> bytes;
  std::uint64_t done = 0;
  // The read-delay hook slows the pieces of zlib's stream: a test of that path.
  std::optional<std::vector<unsigned char>> inflated;
  if (gzip && g_read_delay_ms.load() == 0 && g_whole_member_reads_enabled.load())
    inflated = inflate_voxels(header.iname, static_cast<std::uint64_t>(header.iname_offset), needed);
  constexpr std::size_t k_piece = std::size_t{1} << 20;
  if (inflated) {
    ++g_whole_member_reads;
    bytes = std::move(*inflated);
    done = needed;
  } else {
    const znzFile file = znzopen(header.iname, "rb", gzip);
    if (znz_isnull(file))
      throw_file_error(path, "expected a NIfTI-1 or NIfTI-2 image, found a file libnifti cannot read");
    znzFile handle = file;
    struct Closer {
      znzFile& handle;
      ~Closer() { znzclose(handle); }
    } closer{handle};
    if (znzseek(handle, static_cast<znz_off_t>(header.iname_offset), SEEK_SET) < 0) short_file(0);
    if (!gzip) bytes.resize(static_cast<std::size_t>(needed));
    while (done < needed) {
      if (const int delay = g_read_delay_ms.load(); delay > 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(delay));
      throw_if_cancelled();
      const auto want = static_cast<std::size_t>(std::min<std::uint64_t>(needed - done, k_piece));
      if (done + want > bytes.size())
        bytes.resize(static_cast<std::size_t>(std::min<std::uint64_t>(
            needed, std::max<std::uint64_t>(2 * bytes.size(), std::uint64_t{16} * k_piece))));
      const std::size_t read = znzread(bytes.data() + done, 1, want, handle);
      // znzread passes on gzread's -1 for a damaged stream, as a size_t: far more than was asked.
      if (read > want) {
        throw_file_error(path, "expected gzip-compressed voxels zlib can inflate, found damaged compressed "
                               "data after " +
                                   std::to_string(done) + " bytes of voxels");
      }
      done += read;
      if (read < want) break;
    }
  }
  if (done < needed) short_file(done);
  bytes.resize(static_cast<std::size_t>(needed));
  const bool floats = header.datatype == DT_FLOAT32 || header.datatype == DT_FLOAT64;
  const std::size_t bytes_per_value = header.datatype == DT_FLOAT64 ? 8 : 4;
  const auto swap_unit = static_cast<std::size_t>(header.swapsize);
  const bool swap = header.byteorder != nifti_short_order() && swap_unit > 1;
  // In pieces of 1 MiB (whole values and whole swap units), polling between them.
  for (std::size_t from = 0; from < bytes.size() && (swap || floats); from += k_piece) {
    throw_if_cancelled();
    unsigned char* piece = bytes.data() + from;
    const std::size_t length = std::min(k_piece, bytes.size() - from);
    if (swap) {
      for (std::size_t b = 0; b + swap_unit <= length; b += swap_unit)
        std::reverse(piece + b, piece + b + swap_unit);
    }
    if (!floats) continue;
    for (std::size_t b = 0; b + bytes_per_value <= length; b += bytes_per_value) {
      double value = 0.0;
      if (bytes_per_value == 4) {
        float f = 0.0f;
        std::memcpy(&f, piece + b, 4);
        value = f;
      } else {
        std::memcpy(&value, piece + b, 8);
      }
      // The first value that is not finite, once the file is known to hold every voxel (a short
      // file is named as such, compressed or not).
      if (!std::isfinite(value)) {
        throw_file_error(path, "expected finite values, found " +
                                   std::string(std::isnan(value) ? "NaN" : "infinity") + " at value " +
                                   std::to_string((from + b) / bytes_per_value) + " of " +
                                   std::to_string(header.nvox) + " (i fastest, then j, k, components)");
      }
    }
  }
  return bytes;
}

/// Calls `convert` with a value of the type a real scalar NIfTI datatype names; false (and no
/// call) for any other datatype.
template <typename Convert>
bool with_value_type(int datatype, Convert&& convert) {
  switch (datatype) {
  case DT_UINT8: convert(std::uint8_t{}); return true;
  case DT_INT8: convert(std::int8_t{}); return true;
  case DT_INT16: convert(std::int16_t{}); return true;
  case DT_UINT16: convert(std::uint16_t{}); return true;
  case DT_INT32: convert(std::int32_t{}); return true;
  case DT_UINT32: convert(std::uint32_t{}); return true;
  case DT_INT64: convert(std::int64_t{}); return true;
  case DT_UINT64: convert(std::uint64_t{}); return true;
  case DT_FLOAT32: convert(float{}); return true;
  case DT_FLOAT64: convert(double{}); return true;
  default: return false;
  }
}

/// A NIfTI file's grid and datatype (`values` left empty), its voxels' bytes in this machine's
/// order, and its scaling.
struct RawVolume {
  NiftiVolume volume;
  std::vector<unsigned char> bytes;
  double slope = 1.0, intercept = 0.0;
};

/// Reads a NIfTI file holding `components` values per voxel: a 3-D volume for 1, a 5-D
/// (X, Y, Z, 1, components) image in the ITK vector convention otherwise.
RawVolume read_raw_volume(const std::filesystem::path& path, int components, bool fourth_dimension) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw_file_error(path, "expected a NIfTI file, found " + path_kind(path));
  nifti_set_debug_level(0);
  // The header through libnifti, the voxels by read_voxel_data (in pieces, so that a cancellation
  // need not wait for a whole file to decompress).
  const std::unique_ptr<nifti_image, void (*)(nifti_image*)> image(nifti_image_read(path.c_str(), 0),
                                                                   nifti_image_free);
  check_voxel_offset(path);
  if (!image)
    throw_file_error(path, "expected a NIfTI-1 or NIfTI-2 image, found a file libnifti cannot read");
  RawVolume raw;
  raw.bytes = read_voxel_data(path, *image);
  if (components == 1) {
    for (int d = 4; d <= 7; ++d) {
      if (image->dim[0] >= d && image->dim[d] > 1) {
        throw_file_error(path, "expected a 3-D volume, found dimension " + std::to_string(d) + " of size " +
                                   std::to_string(image->dim[d]));
      }
    }
  } else if (fourth_dimension) {
    if (image->dim[0] != 4 || image->dim[4] != components) {
      std::string found = "dimensions (";
      for (int d = 1; d <= image->dim[0]; ++d)
        found += (d > 1 ? ", " : "") + std::to_string(image->dim[d]);
      throw_file_error(path, "expected a 4-D vector image (X, Y, Z, " + std::to_string(components) +
                                 "), found " + found + ")");
    }
  } else {
    const std::string expected =
        "expected a 5-D vector image (X, Y, Z, 1, " + std::to_string(components) + ") in the ITK convention";
    if (image->dim[0] == 4 && image->dim[4] == components) {
      throw_file_error(path, expected + ", found a 4-D (X, Y, Z, " + std::to_string(components) +
                                 ") volume, which ITK and elastix read as a time series");
    }
    if (image->dim[0] < 5 || image->dim[4] != 1 || image->dim[5] != components ||
        (image->dim[0] >= 6 && image->dim[6] > 1) || (image->dim[0] >= 7 && image->dim[7] > 1)) {
      std::string found = "dimensions (";
      for (int d = 1; d <= image->dim[0]; ++d)
        found += (d > 1 ? ", " : "") + std::to_string(image->dim[d]);
      throw_file_error(path, expected + ", found " + found + ")");
    }
  }
  NiftiVolume& volume = raw.volume;
  volume.datatype = image->datatype;
  volume.grid.dims =
      Eigen::Vector3i(static_cast<int>(image->nx), static_cast<int>(std::max<std::int64_t>(1, image->ny)),
                      static_cast<int>(std::max<std::int64_t>(1, image->nz)));
  Eigen::Matrix4d affine = Eigen::Matrix4d::Identity();
  const nifti_dmat44* source = image->sform_code > 0   ? &image->sto_xyz
                               : image->qform_code > 0 ? &image->qto_xyz
                                                       : nullptr;
  if (source) {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c)
        affine(r, c) = source->m[r][c];
  } else {
    affine.diagonal().head<3>() = Eigen::Vector3d(image->dx, image->dy, image->dz);
  }
  const Eigen::Matrix3d linear = affine.topLeftCorner<3, 3>();
  const Eigen::Vector3d spacing = linear.colwise().norm().transpose();
  if ((spacing.array() <= 0.0).any())
    throw_file_error(path, "expected positive voxel sizes, found a zero column in the affine");
  const Eigen::Matrix3d direction = linear * spacing.cwiseInverse().asDiagonal();
  const double shear =
      (direction.transpose() * direction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (shear > 1e-4) {
    throw_file_error(
        path,
        "expected an affine without shear (rotation times voxel sizes), found axes whose dot products differ "
        "from 0 by " +
            std::to_string(shear));
  }
  volume.grid.spacing_mm = spacing;
  volume.grid.world_from_voxel = affine;

  raw.slope = image->scl_slope != 0.0 ? image->scl_slope : 1.0;
  raw.intercept = image->scl_slope != 0.0 ? image->scl_inter : 0.0;
  if (!with_value_type(image->datatype, [](auto) {})) {
    throw_file_error(path, "expected a real scalar datatype, found NIfTI datatype " +
                               std::to_string(image->datatype) + " (" +
                               nifti_datatype_string(image->datatype) + ")");
  }
  return raw;
}

NiftiVolume read_volume(const std::filesystem::path& path, int components, bool fourth_dimension = false) {
  RawVolume raw = read_raw_volume(path, components, fourth_dimension);
  NiftiVolume volume = std::move(raw.volume);
  // The bytes hold values of type T (memcpy: the buffer is of bytes, not of T).
  with_value_type(volume.datatype, [&](auto type) {
    using T = decltype(type);
    const std::size_t count = raw.bytes.size() / sizeof(T);
    volume.values.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      T value;
      std::memcpy(&value, raw.bytes.data() + i * sizeof(T), sizeof(T));
      volume.values[i] = raw.slope * static_cast<double>(value) + raw.intercept;
    }
  });
  return volume;
}

} // namespace

NiftiVolume read_nifti(const std::filesystem::path& path) {
  return read_volume(path, 1);
}

NiftiVolume read_nifti_vectors(const std::filesystem::path& path, int components) {
  return read_volume(path, components);
}

NiftiVolume read_nifti_vectors_4d(const std::filesystem::path& path, int components) {
  return read_volume(path, components, true);
}

std::vector<std::int32_t> read_nifti_labels(const std::filesystem::path& path, ImageGrid* grid) {
  const RawVolume raw = read_raw_volume(path, 1, false);
  const Eigen::Vector3i& d = raw.volume.grid.dims;
  std::vector<std::int32_t> labels;
  const bool unscaled = raw.slope == 1.0 && raw.intercept == 0.0;
  with_value_type(raw.volume.datatype, [&](auto type) {
    using T = decltype(type);
    const std::size_t count = raw.bytes.size() / sizeof(T);
    labels.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      T value;
      std::memcpy(&value, raw.bytes.data() + i * sizeof(T), sizeof(T));
      // Integers of up to 32 bits, unscaled, are labels as they are (most label files).
      if constexpr (std::is_integral_v<T> && sizeof(T) <= 4 && !std::is_same_v<T, std::uint32_t>) {
        // (-2^31 is not a label: its magnitude is beyond int32's, as the check below says)
        const bool representable = !std::is_same_v<T, std::int32_t> || value != std::numeric_limits<T>::min();
        if (unscaled && representable) {
          labels[i] = static_cast<std::int32_t>(value);
          continue;
        }
      }
      const double v = raw.slope * static_cast<double>(value) + raw.intercept;
      if (!std::isfinite(v) || v != std::round(v) || std::abs(v) > std::numeric_limits<std::int32_t>::max()) {
        const auto index = static_cast<std::int64_t>(i);
        throw_file_error(path, "expected whole-number labels, found " + std::to_string(v) + " at voxel (" +
                                   std::to_string(index % d.x()) + ", " +
                                   std::to_string(index / d.x() % d.y()) + ", " +
                                   std::to_string(index / (static_cast<std::int64_t>(d.x()) * d.y())) + ")");
      }
      labels[i] = static_cast<std::int32_t>(v);
    }
  });
  if (grid) *grid = raw.volume.grid;
  return labels;
}

void set_read_delay_for_testing(int milliseconds_per_piece) {
  g_read_delay_ms = milliseconds_per_piece;
}

void set_whole_member_reads_for_testing(bool enabled) {
  g_whole_member_reads_enabled = enabled;
}

std::size_t whole_member_reads_for_testing() {
  return g_whole_member_reads.load();
}

} // namespace phantasm
