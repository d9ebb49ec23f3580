#include "apps/phantasm/commands.hpp"
#include "batch/sweep.hpp"
#include "core/error.hpp"
#include "scene/scene.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_validate_command(CLI::App& app, std::function<int()>& action) {
  auto files = std::make_shared<std::vector<std::string>>();
  CLI::App* command = app.add_subcommand(
      "validate",
      "Check scene and sweep files and report every problem as file:line:column: key: expected, found");
  command->add_option("files", *files, "Scene or sweep files (YAML); a sweep's every subject is checked")
      ->required();
  command->callback([files, &action] {
    action = [files] {
      int exit_code = exit_ok;
      for (const auto& file : *files) {
        // Read once: a pipe (`validate <(...)`) gives its text to one reader only.
        std::string text;
        const bool readable = read_scene_text(file, text).empty();
        if (readable && is_sweep_text(text)) {
          try {
            const Sweep sweep = parse_sweep(text, file, SweepDepth::sample);
            std::cout << file << ": valid sweep of " << sweep.subject_count << " subjects";
            if (sweep.subjects.size() < sweep.subject_count) {
              std::cout << " (" << sweep.subjects.size()
                        << " checked: the first, the last and every listed value; batch checks them all)";
            }
            std::cout << '\n';
          } catch (const InputError& error) {
            std::cerr << error.what() << '\n';
            exit_code = exit_bad_input;
          }
          continue;
        }
        const SceneLoadResult result = readable ? parse_scene(text, file) : load_scene(file);
        if (result.problems.empty()) {
          std::cout << file << ": valid\n";
        } else {
          std::cerr << format_diagnostics(result.problems);
          exit_code = exit_bad_input;
        }
      }
      return exit_code;
    };
  });
}

} // namespace phantasm::cli
