#include "io/json_file.hpp"

#include "io/atomic_file.hpp"

namespace phantasm {

void write_json_file(const std::filesystem::path& path, const nlohmann::json& value) {
  write_file_atomically(path, value.dump(2) + "\n");
}

} // namespace phantasm
