// Reading a JSON file (io/json_file.hpp): the value as written, and a file that is missing or is
// not JSON refused with a message naming the file, what it should hold, and where it stops.

#include "io/json_file.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

TEST(JsonFile, ReadsWhatWasWrittenAndNamesTheFileOfAMissingOrBrokenOne) {
  const fs::path folder = fresh_folder("json-file");
  const nlohmann::json value = {{"bodies", {{{"organ", "csf"}, {"inverted_tets", 0}}}}};
  write_json_file(folder / "provenance.json", value);
  EXPECT_EQ(read_json_file(folder / "provenance.json", "a provenance"), value);

  const std::string missing =
      input_error_message([&] { read_json_file(folder / "absent.json", "the JSON phantasm writes"); });
  EXPECT_NE(missing.find((folder / "absent.json").string() + ": expected the JSON phantasm writes, found no "
                                                             "readable file"),
            std::string::npos)
      << missing;

  write_text_file(folder / "cut.json", "{\n  \"bodies\": [\n");
  const std::string cut = input_error_message([&] { read_json_file(folder / "cut.json", "a provenance"); });
  EXPECT_NE(cut.find((folder / "cut.json").string() + ":3:"), std::string::npos) << cut;
  EXPECT_NE(cut.find("expected a provenance"), std::string::npos) << cut;
  fs::remove_all(folder);
}
