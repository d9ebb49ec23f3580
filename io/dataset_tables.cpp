#include "io/dataset_tables.hpp"

#include "core/error.hpp"
#include "core/path_kind.hpp"

#include <fstream>
#include <sstream>

namespace phantasm {

std::vector<LandmarkRow> read_landmarks(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in || path_kind(path) != "a regular file")
    throw InputError(path.string() + ": expected the subject's landmarks (CSV), found " + path_kind(path));
  std::vector<LandmarkRow> rows;
  std::string line;
  int number = 0;
  constexpr const char* k_header = "name,organ,x_mm,y_mm,z_mm";
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (number == 1) {
      if (line != k_header)
        throw InputError(path.string() + ":1: expected the header " + k_header + ", found '" + line + "'");
      continue;
    }
    if (line.empty()) continue;
    std::stringstream fields(line);
    LandmarkRow row;
    std::string x, y, z;
    if (!std::getline(fields, row.name, ',') || !std::getline(fields, row.organ, ',') ||
        !std::getline(fields, x, ',') || !std::getline(fields, y, ',') || !std::getline(fields, z)) {
      throw InputError(path.string() + ":" + std::to_string(number) +
                       ": expected name,organ,x_mm,y_mm,z_mm, found '" + line + "'");
    }
    try {
      row.ras_mm = Eigen::Vector3d(std::stod(x), std::stod(y), std::stod(z));
    } catch (const std::exception&) {
      throw InputError(path.string() + ":" + std::to_string(number) + ": expected three numbers, found '" +
                       line + "'");
    }
    if (!row.ras_mm.allFinite()) {
      throw InputError(path.string() + ":" + std::to_string(number) +
                       ": expected three finite numbers (mm), found '" + line + "'");
    }
    rows.push_back(row);
  }
  if (number == 0)
    throw InputError(path.string() + ": expected the header " + std::string(k_header) +
                     " and a line per landmark, found an empty file");
  return rows;
}

std::map<std::int32_t, std::string> read_label_names(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in || path_kind(path) != "a regular file")
    throw InputError(path.string() + ": expected the dataset's label table, found " + path_kind(path));
  std::map<std::int32_t, std::string> names;
  std::string line;
  std::getline(in, line); // header
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string index, name;
    if (std::getline(fields, index, '\t') && std::getline(fields, name, '\t')) {
      try {
        names[std::stoi(index)] = name;
      } catch (const std::exception&) {
        throw InputError(path.string() + ": expected an integer label index, found '" + index + "'");
      }
    }
  }
  return names;
}

} // namespace phantasm
