// Texture and tissue regions through the phantasm command (docs/volumes-and-images.md, "Tissue
// regions and texture"): the deformed state's parameter maps are the reference maps carried by
// the exact map (tests/apps/check_texture_moves.py), and bad texture or region settings stop the
// run with the file, tissue or label named, nothing written.

#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// The small head with `extra` appended, written to folder/scene.yaml.
fs::path small_head_with(const fs::path& folder, const std::string& extra) {
  fs::create_directories(folder);
  write_text_file(folder / "scene.yaml", read_file(k_small_scene) + "\n" + extra);
  return folder / "scene.yaml";
}

/// A smooth scan on a 1.5 mm grid centred on the origin, `half_mm` wide each way.
fs::path smooth_scan(const fs::path& path, double half_mm) {
  phantasm::ImageGrid grid;
  const int n = static_cast<int>(std::ceil(2.0 * half_mm / 1.5)) + 1;
  grid.dims = Eigen::Vector3i(n, n, n);
  grid.spacing_mm = Eigen::Vector3d::Constant(1.5);
  grid.world_from_voxel = Eigen::Matrix4d::Identity();
  grid.world_from_voxel.topLeftCorner<3, 3>() *= 1.5;
  grid.world_from_voxel.block<3, 1>(0, 3) = Eigen::Vector3d::Constant(-half_mm);
  std::vector<float> values(static_cast<std::size_t>(grid.voxel_count()));
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        values[static_cast<std::size_t>(i + n * (j + n * k))] =
            static_cast<float>(100.0 + 12.0 * std::sin(0.3 * x.x()) * std::cos(0.25 * x.y()) + 0.2 * x.z());
      }
  phantasm::write_nifti(path, grid, values, {});
  return path;
}

void expect_texture_moves(const fs::path& out) {
  const CommandResult check = run_command(
      {PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_texture_moves.py").string(), out.string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  std::printf("%s", check.out.c_str());
}

} // namespace

// A random texture, a scan texture and a random texture with the scan's spectrum: in each, the deformed T1
// and PD maps are the reference maps warped through the ground-truth field inside the exact mask (and not the
// unwarped ones); the maps' sidecars and the provenance record the texture.
TEST(MaterialMapsRun, TextureMovesWithTheTissue) {
  const fs::path root = fresh_folder("texture-moves");
  for (const std::string& texture :
       {std::string("texture: {source: random, correlation_mm: 4, random_sd: 0.08}"),
        // the scan named relative to the scene's folder, as organs' files are; the T1 gains
        // matched to the T1w's contrast
        "texture: {source: scan, tissues: [gray_matter, white_matter], match: T1w, scan: " +
            smooth_scan(root / "scan.nii.gz", 70.0).filename().string() + "}",
        // a field per tissue with the spectrum measured on the scan
        std::string(
            "texture: {source: random, spectrum: scan, PD_gain: 1, tissues: [gray_matter, white_matter], "
            "scan: scan.nii.gz}")}) {
    SCOPED_TRACE(texture);
    const fs::path out = root / "out";
    const CommandResult run = run_command(
        {k_phantasm, "run", small_head_with(root, texture).string(), "-o", out.string(), "-q", "--force"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    expect_texture_moves(out);
    const fs::path anat = out / "derivatives" / "phantasm" / "sub-01" / "ses-def" / "anat";
    const auto sidecar = nlohmann::json::parse(read_file(anat / "sub-01_ses-def_T1map.json"));
    EXPECT_NE(sidecar.at("Texture").get<std::string>().find("exact map"), std::string::npos)
        << sidecar.dump();
    EXPECT_EQ(nlohmann::json::parse(read_file(anat / "sub-01_ses-def_T2map.json")).at("Texture"), "none");
    const std::string provenance = read_file(out / "derivatives" / "phantasm" / "sub-01" / "provenance.json");
    EXPECT_NE(provenance.find("\"texture\""), std::string::npos);
    if (texture.find("match: T1w") != std::string::npos) { // each tissue's matched gain recorded
      EXPECT_NE(sidecar.at("Texture").get<std::string>().find("so that T1w's signal changes by d"),
                std::string::npos)
          << sidecar.dump();
      EXPECT_NE(provenance.find("texture white_matter T1 gain"), std::string::npos);
    }
    if (texture.find("spectrum: scan") != std::string::npos) { // the measured figures recorded
      EXPECT_NE(sidecar.at("Texture").get<std::string>().find("white_matter sd "), std::string::npos)
          << sidecar.dump();
    }
  }
}

// Bad settings: a texture scan that does not cover the anatomy (named, with the tissue), a
// region's tissue without the values a sequence needs at the field strength, a region of an organ
// that is not an atlas's, a region named like an organ, a textured tissue the phantom lacks, spectrum: scan
// without a random source, a spectrum's scan that does not cover the anatomy, a match naming no sequence or
// without a texture: exit 2, nothing written.
TEST(MaterialMapsRun, BadTextureAndRegionSettingsAreNamedAndNothingIsWritten) {
  const fs::path root = fresh_folder("texture-bad");
  const fs::path small_scan = smooth_scan(root / "small.nii.gz", 20.0);
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"texture: {source: scan, scan: " + small_scan.string() + "}",
       {small_scan.string(), "covers the anatomy", "texture.scan"}},
      {"tissue_regions:\n  - {organ: white_matter, label: caudate, tissue: pons}\n",
       {"tissue_regions[0].organ", "label volume of an atlas", "pons", "T1_ms"}},
      // a region's dseg name that an organ has
      {"tissue_regions:\n  - {organ: white_matter, label: csf, tissue: csf, name: grey_matter}\n",
       {"tissue_regions[0].name", "names no organ and no other region", "'grey_matter' again"}},
      {"texture: {source: random, tissues: [bone_marrow]}", {"texture.tissues[0]", "bone_marrow"}},
      {"texture: {source: scan, spectrum: scan}", {"texture.spectrum", "source: random"}},
      {"texture: {source: random, spectrum: scan, scan: " + small_scan.string() + "}",
       {small_scan.string(), "covers the anatomy", "texture.scan"}},
      {"texture: {source: random, match: T2star}", {"texture.match", "T1w, T2w", "'T2star'"}},
      {"texture: {match: T1w}", {"texture.match", "source: none"}},
  };
  for (const auto& [extra, expected] : cases) {
    SCOPED_TRACE(extra);
    const fs::path out = root / "out";
    const CommandResult run = run_command(
        {k_phantasm, "run", small_head_with(root / "case", extra).string(), "-o", out.string(), "-q"});
    EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
    for (const std::string& text : expected)
      EXPECT_NE(run.err.find(text), std::string::npos) << text << " not in:\n" << run.err;
    EXPECT_FALSE(fs::exists(out)) << "a rejected run wrote " << out;
  }
}
