#include "io/vdb_file.hpp"

#include "core/abandonable_work.hpp"
#include "core/byte_codec.hpp"
#include "io/atomic_file.hpp"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <unistd.h>

#include <sstream>
#include <stdexcept>
#include <system_error>

namespace phantasm {
namespace {

openvdb::math::Transform::Ptr transform_of(const ImageGrid& grid) {
  // OpenVDB matrices act on row vectors: the transpose of world_from_voxel.
  openvdb::math::Mat4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      m(c, r) = grid.world_from_voxel(r, c);
  return openvdb::math::Transform::createLinearTransform(m);
}

/// What a grid holds, as string metadata that pyopenvdb and OpenVDB's tools show.
void describe(openvdb::GridBase& grid, const std::string& units, const std::string& description) {
  grid.insertMeta("frame",
                  openvdb::StringMetadata("RAS (world millimetres; the transform maps index to RAS mm)"));
  grid.insertMeta("units", openvdb::StringMetadata(units));
  grid.insertMeta("description", openvdb::StringMetadata(description));
}

template <typename GridType, typename Value>
typename GridType::Ptr sparse_grid(const ImageGrid& grid, const std::vector<Value>& values,
                                   const std::string& name) {
  auto out = GridType::create(typename GridType::ValueType(0));
  out->setTransform(transform_of(grid));
  out->setName(name);
  auto accessor = out->getAccessor();
  std::size_t v = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i, ++v)
        if (values[v] != Value(0))
          accessor.setValue(openvdb::Coord(i, j, k), static_cast<typename GridType::ValueType>(values[v]));
  return out;
}

} // namespace

void write_vdb(const std::filesystem::path& path, const VdbContents& contents) {
  openvdb::initialize();
  openvdb::GridPtrVec grids;
  for (const auto& [organ, level_set] : contents.level_sets) {
    auto copy = static_cast<const openvdb::FloatGrid*>(level_set)->deepCopy();
    copy->setName(organ + "_sdf");
    describe(*copy, "mm", "signed distance to the surface of " + organ + ", negative inside");
    grids.push_back(copy);
  }
  if (contents.grid && contents.labels) {
    // A FloatGrid, not an Int32Grid: pyopenvdb reads only Bool, Float and Vec3S grids and fails
    // on the whole file otherwise. Labels are small integers, which float holds exactly.
    auto labels = sparse_grid<openvdb::FloatGrid>(*contents.grid, *contents.labels, "labels");
    describe(*labels, "label",
             "dseg label value per voxel (integers stored as float; names in the dataset's dseg.tsv), "
             "0 outside every organ");
    grids.push_back(labels);
  }
  for (const auto& [tissue, fractions] : contents.fractions) {
    auto grid = sparse_grid<openvdb::FloatGrid>(*contents.grid, fractions(), "fraction_" + tissue);
    describe(*grid, "1", "fraction of each voxel's volume that is " + tissue + " (0 to 1)");
    grids.push_back(grid);
  }
  // OpenVDB writes to a path: a hidden temporary next to the final name, then rename, as
  // AtomicFileWriter does (it also removes the temporary if anything throws).
  std::filesystem::create_directories(path.parent_path());
  const std::filesystem::path temporary =
      path.parent_path() /
      ("." + path.filename().string() + ".phantasm-tmp-" + std::to_string(::getpid()) + "-vdb");
  RegisteredTemporary registration(temporary);
  try {
    {
      // OpenVDB compresses and writes in one call that polls nothing: a cancelled run may be
      // abandoned inside it (the watchdog removes the registered temporary first).
      const AbandonableWork writing;
      openvdb::io::File file(temporary.string());
      file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
      file.write(grids);
      file.close();
    }
    if (const int error = registration.rename_to(path); error != 0)
      throw std::filesystem::filesystem_error("cannot rename", temporary, path,
                                              std::error_code(error, std::generic_category()));
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

std::string encode_float_grids(const std::vector<const void*>& grids) {
  openvdb::initialize();
  openvdb::GridCPtrVec named;
  for (std::size_t g = 0; g < grids.size(); ++g) {
    // A copy that shares the tree, named by its position so that the reader finds the order.
    const openvdb::FloatGrid::Ptr copy =
        std::const_pointer_cast<openvdb::FloatGrid>(static_cast<const openvdb::FloatGrid*>(grids[g])->copy());
    copy->setName(std::to_string(g));
    named.push_back(copy);
  }
  std::ostringstream out(std::ios::binary);
  openvdb::io::Stream stream(out);
  // Lossless: inactive values that are not the background are stored (no half floats).
  stream.setCompression(openvdb::io::COMPRESS_ACTIVE_MASK);
  stream.setGridStatsMetadataEnabled(false);
  stream.write(named);
  // The header holds a random UUID per write; the nil UUID in its place makes the bytes a
  // function of the grids (the reader takes any UUID), so that caches written by shards and
  // restarts are the same files.
  std::string bytes = std::move(out).str();
  const std::string tag = stream.getUniqueTag();
  const std::string nil = "00000000-0000-0000-0000-000000000000";
  if (const std::size_t at = bytes.find(tag); tag.size() == nil.size() && at != std::string::npos)
    bytes.replace(at, nil.size(), nil);
  return bytes;
}

std::vector<std::shared_ptr<void>> decode_float_grids(std::string_view bytes) {
  openvdb::initialize();
  openvdb::GridPtrVecPtr read;
  try {
    std::istringstream in(std::string(bytes), std::ios::binary);
    openvdb::io::Stream stream(in);
    read = stream.getGrids();
  } catch (const openvdb::Exception& error) {
    throw DamagedBytes(std::string("level-set grids: ") + error.what());
  }
  std::vector<std::shared_ptr<void>> out(read ? read->size() : 0);
  for (const openvdb::GridBase::Ptr& grid : read ? *read : openvdb::GridPtrVec()) {
    const openvdb::FloatGrid::Ptr floats = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
    std::size_t position = out.size();
    try {
      position = std::stoul(grid->getName());
    } catch (const std::exception&) {
    }
    if (!floats || position >= out.size() || out[position])
      throw DamagedBytes("level-set grids: a grid that is not the float grid '" + grid->getName() +
                         "' of the order written");
    out[position] = floats;
  }
  return out;
}

} // namespace phantasm
