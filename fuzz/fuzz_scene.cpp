// libFuzzer target: scene text parsed and validated into the stages' settings, as `phantasm
// validate` and `run` read a scene. parse_scene never throws for bad input: every problem is a
// diagnostic "file:line:column: key: expected ..., found ...". Any exception, a result that is
// neither a scene nor a problem, a diagnostic without "expected"/"found" or outside the text, or
// settings that cannot be written as provenance JSON are findings.
#include "fuzz/fuzz_support.hpp"
#include "scene/scene.hpp"
#include "scene/scene_json.hpp"

#include <algorithm>
#include <cstdint>
#include <string>

using namespace phantasm;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Relative mesh and label paths resolve against the test scenes' folder, as in the test suite.
  static const std::filesystem::path file =
      std::filesystem::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "fuzz-input.yaml";
  try {
    const SceneLoadResult result = parse_scene(text, file);
    if (result.scene.has_value() == !result.problems.empty())
      fuzz::finding("parse_scene returned " + std::to_string(result.problems.size()) + " problems and " +
                    (result.scene ? "a scene" : "no scene"));
    const long lines = std::count(text.begin(), text.end(), '\n') + 1;
    for (const Diagnostic& problem : result.problems) {
      const std::string message = problem.format();
      if (problem.where.file != file.string() || problem.where.line < 0 || problem.where.line > lines + 1 ||
          problem.where.column < 0)
        fuzz::finding("a diagnostic outside the scene text (" + std::to_string(lines) +
                      " lines): " + message);
      if (problem.message.find("expected") == std::string::npos ||
          problem.message.find("found") == std::string::npos)
        fuzz::finding("a diagnostic that does not say what was expected and found: " + message);
    }
    if (result.scene) {
      // What provenance.json and `phantasm info --json` write of the scene.
      (void)scene_settings_json(*result.scene).dump(2);
    }
  } catch (const std::exception& error) {
    fuzz::unexpected_exception("parse_scene", &error);
  }
  return 0;
}
