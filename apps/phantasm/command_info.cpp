#include "apps/phantasm/commands.hpp"
#include "io/json_file.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene_json.hpp"
#include "scene/settings_declarations.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_info_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string scene;
    bool json = false;
    bool settings = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "info", "Show what a scene models: grid, organs, tissues, sequences and each stage's plan");
  command->add_option("scene", options->scene, "Scene file (YAML)")->required();
  command->add_flag("--json", options->json, "Print every setting, defaults filled in, as JSON");
  command->add_flag("--settings", options->settings,
                    "Print every declared setting of the stages: value, type, unit, bounds, default and "
                    "the cached results it shapes");
  command->callback([options, &action] {
    action = [options] {
      const SceneLoadResult result = load_scene(options->scene);
      if (!result.scene) {
        std::cerr << format_diagnostics(result.problems);
        return static_cast<int>(exit_bad_input);
      }
      const Scene& scene = *result.scene;
      if (options->json) {
        std::cout << json_text(scene_settings_json(scene)) << '\n';
        return static_cast<int>(exit_ok);
      }
      if (options->settings) {
        for (const std::string& row : settings_table(scene))
          std::cout << row << '\n';
        return static_cast<int>(exit_ok);
      }
      const ImageGrid grid = scene.grid.grid();
      std::cout << "scene " << scene.name << " (" << scene.file.string() << ", sha256 "
                << scene.sha256.substr(0, 12) << ")\nseed " << scene.seed << ", "
                << scene.mri.field_strength_T << " T, grid " << grid.dims.x() << " x " << grid.dims.y()
                << " x " << grid.dims.z() << " (" << grid.voxel_count() << " voxels)\n";
      for (const auto& stage : plan_stages(scene)) {
        std::cout << "\n" << stage.stage << (stage.status == "skipped" ? " (skipped)" : "") << ":\n";
        for (const auto& line : stage.modelled)
          std::cout << "  " << line << '\n';
        for (const auto& line : stage.skipped)
          std::cout << "  skipped: " << line << '\n';
      }
      // The cost before the work: each organ's effective settings, what the run builds and
      // needs, against what this machine has.
      const CostEstimate estimate = estimate_cost(scene);
      std::cout << "\nestimate (docs/architecture.md, Cost estimate):\n";
      for (const auto& line : cost_lines(estimate))
        std::cout << "  " << line << '\n';
      const double available = available_memory_bytes();
      if (available > 0.0) {
        std::cout << "  memory available on this machine: " << format_bytes(available)
                  << (estimate.peak_memory_bytes > available
                          ? " (less than the estimated peak: run refuses it)"
                          : "")
                  << '\n';
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
