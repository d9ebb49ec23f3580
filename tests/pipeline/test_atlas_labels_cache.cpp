// The atlas labels cache (pipeline/atlas_labels_cache.hpp): the Colin 27 labels derived with the
// cache cold (derived and stored) and warm (read) are those derived without it, provenance lines
// included; a damaged entry is derived again; the key follows the inputs' bytes.

#include "core/byte_codec.hpp"
#include "pipeline/atlas_labels_cache.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

void expect_same_labels(const AtlasLabels& a, const AtlasLabels& b) {
  EXPECT_EQ(a.head.grid.dims, b.head.grid.dims);
  EXPECT_EQ(a.head.grid.spacing_mm, b.head.grid.spacing_mm);
  EXPECT_EQ(a.head.grid.world_from_voxel, b.head.grid.world_from_voxel);
  EXPECT_TRUE(a.head.labels == b.head.labels);
  ASSERT_EQ(a.head.table.size(), b.head.table.size());
  for (std::size_t k = 0; k < a.head.table.size(); ++k) {
    EXPECT_EQ(a.head.table[k].label, b.head.table[k].label);
    EXPECT_EQ(a.head.table[k].name, b.head.table[k].name);
    EXPECT_EQ(a.head.table[k].tissue, b.head.table[k].tissue);
  }
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.provenance, b.provenance);
}

} // namespace

TEST(AtlasLabelsCache, ColdWarmAndDamagedGiveTheLabelsDerivedWithoutIt) {
  const fs::path folder = fresh_folder("atlas-labels-cache");
  Reporter quiet = Reporter::silent();
  const AtlasLabels derived = derive_atlas_labels("colin27");
  ASSERT_GT(derived.head.labels.size(), 1000000u);
  const AtlasLabels cold = derive_atlas_labels_cached("colin27", folder, quiet);
  const std::vector<fs::path> entries = cache_entries(folder, "atlas-");
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_NE(
      entries[0].filename().string().find(atlas_labels_cache_key("colin27", default_colin27_templates_dir())),
      std::string::npos);
  const AtlasLabels warm = derive_atlas_labels_cached("colin27", folder, quiet);
  expect_same_labels(cold, derived);
  expect_same_labels(warm, derived);
  const std::string stored = read_file(entries[0]);
  write_text_file(entries[0], stored.substr(0, stored.size() - 100));
  expect_same_labels(derive_atlas_labels_cached("colin27", folder, quiet), derived);
  EXPECT_TRUE(read_file(entries[0]) == stored); // stored anew, whole

  // Encoded again, the same bytes; cut short or with bytes after, DamagedBytes.
  const std::string bytes = encode_atlas_labels(derived);
  EXPECT_TRUE(encode_atlas_labels(decode_atlas_labels(bytes)) == bytes);
  EXPECT_THROW(decode_atlas_labels(std::string_view(bytes).substr(0, bytes.size() - 1)), DamagedBytes);
  EXPECT_THROW(decode_atlas_labels(bytes + "x"), DamagedBytes);
}

// The key changes with the bytes of an input (a copy of the templates with one file changed),
// and there is none when an input is missing (the derivation then names it).
TEST(AtlasLabelsCache, TheKeyFollowsTheInputsBytes) {
  const fs::path templates = fresh_folder("atlas-labels-inputs");
  for (const fs::path& input : atlas_input_files("colin27", default_colin27_templates_dir()))
    fs::copy_file(input, templates / input.filename());
  const std::string key = atlas_labels_cache_key("colin27", templates);
  ASSERT_EQ(key.size(), 64u);
  EXPECT_EQ(atlas_labels_cache_key("colin27", templates), key);
  write_text_file(templates / "aal.nii.gz", read_file(templates / "aal.nii.gz") + "x");
  EXPECT_NE(atlas_labels_cache_key("colin27", templates), key);
  fs::remove(templates / "aal.nii.gz");
  EXPECT_TRUE(atlas_labels_cache_key("colin27", templates).empty());
}
