// The elastix registration study (scripts/registration_study.py) on one magnitude with short
// optimizations: registration brings the landmarks closer than no registration does.

#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

using namespace phantasm::testing;
namespace fs = std::filesystem;

// The registration study on one magnitude with short optimizations: elastix (affine + B-spline,
// the shipped parameter files) brings the landmarks closer than no registration does.
TEST(RegistrationStudy, ElastixReducesTheTargetRegistrationError) {
  const fs::path folder = fresh_folder("study");
  const CommandResult study =
      run_command({PHANTASM_PYTHON, (k_source_dir / "scripts" / "registration_study.py").string(), "-o",
                   folder.string(), "--magnitudes", "6", "--iterations", "150", "--phantasm", k_phantasm});
  ASSERT_EQ(study.exit_code, 0) << study.out << study.err;
  const nlohmann::json result = nlohmann::json::parse(read_file(folder / "study.json"));
  ASSERT_EQ(result["rows"].size(), 1u);
  const auto& row = result["rows"][0];
  EXPECT_GT(row["tre_mean_mm_none"].get<double>(), 1.0);
  EXPECT_LT(row["tre_mean_mm_elastix"].get<double>(), 0.75 * row["tre_mean_mm_none"].get<double>());
  EXPECT_GT(row["mean_dice_elastix"].get<double>(), row["mean_dice_none"].get<double>());
  EXPECT_TRUE(fs::file_size(folder / "study.png") > 1000);
  EXPECT_TRUE(fs::exists(folder / "study.csv"));
}
