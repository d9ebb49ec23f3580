// Tables of a phantasm dataset read back by its clients (evaluation, the report): the landmarks
// (ses-*/landmarks/*_landmarks.csv: name,organ,x_mm,y_mm,z_mm in RAS mm) and the label table
// (dseg.tsv), each with a message naming the file and line of anything else.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace phantasm {

struct LandmarkRow {
  std::string name, organ;
  Eigen::Vector3d ras_mm;
};

/// @throws InputError naming the file (and line) for a missing file, another header, a row
/// that is not name,organ and three finite numbers
std::vector<LandmarkRow> read_landmarks(const std::filesystem::path& path);

/// Label index -> organ name, from dseg.tsv ("index<TAB>name<TAB>tissue").
/// @throws InputError naming the file for a missing file or a label index that is not an integer
std::map<std::int32_t, std::string> read_label_names(const std::filesystem::path& path);

} // namespace phantasm
