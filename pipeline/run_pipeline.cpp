#include "pipeline/run_pipeline.hpp"

#include "anatomy/anatomy_plan.hpp"
#include "core/cancellation.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "mri/mri_plan.hpp"
#include "scene/scene_json.hpp"
#include "sim/sim_plan.hpp"
#include "voxelize/voxelize_plan.hpp"

#include <sstream>

namespace phantasm {
namespace {

nlohmann::json stage_json(const StageReport& report) {
  return {{"stage", report.stage},
          {"status", report.status},
          {"modelled", report.modelled},
          {"skipped", report.skipped},
          {"accuracy", report.accuracy}};
}

nlohmann::json generated_by() {
  return nlohmann::json::array(
      {{{"Name", "phantasm"},
        {"Version", version},
        {"Description", "Deformable anatomical MRI phantom with exact ground truth"}}});
}

std::string dseg_table(const Scene& scene) {
  std::ostringstream text;
  text << "index\tname\ttissue\n0\tbackground\tbackground\n";
  int index = 1;
  for (const auto& organ : scene.anatomy.organs)
    text << index++ << '\t' << organ.name << '\t' << organ.tissue << '\n';
  return text.str();
}

/// Writes files in order, with a progress bar, and remembers what was written.
class DatasetWriter {
public:
  DatasetWriter(const DatasetLayout& layout, Reporter& reporter, std::size_t expected_files)
      : m_layout(layout), m_progress(reporter, "writing", expected_files) {}

  void text(const std::filesystem::path& path, const std::string& content) {
    write_file_atomically(path, content);
    done(path);
  }
  void json(const std::filesystem::path& path, const nlohmann::json& content) {
    write_json_file(path, content);
    done(path);
  }
  const std::vector<std::filesystem::path>& files() const { return m_files; }

private:
  void done(const std::filesystem::path& path) {
    m_files.push_back(std::filesystem::relative(path, m_layout.root()));
    m_progress.advance();
    throw_if_cancelled();
  }

  const DatasetLayout& m_layout;
  ProgressBar m_progress;
  std::vector<std::filesystem::path> m_files;
};

} // namespace

std::vector<StageReport> plan_stages(const Scene& scene) {
  return {plan_anatomy(scene), plan_sim(scene), plan_voxelize(scene), plan_mri(scene)};
}

RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter) {
  prepare_output_folder(options.output, options.force);
  RunSummary summary;
  summary.stages = plan_stages(scene);
  for (const auto& stage : summary.stages) {
    for (const auto& line : stage.modelled)
      reporter.modelled(stage.stage, line);
    for (const auto& line : stage.skipped)
      reporter.skipped(stage.stage, line);
    if (stage.status == "planned") {
      reporter.modelled(stage.stage,
                        "planned only: this version records the plan; the stage itself does not run yet");
    }
  }

  const DatasetLayout layout(options.output, scene.outputs.subject);
  DatasetWriter writer(layout, reporter, 6);
  writer.json(layout.dataset_description(), {{"Name", scene.name},
                                             {"BIDSVersion", "1.9.0"},
                                             {"DatasetType", "raw"},
                                             {"GeneratedBy", generated_by()}});
  writer.json(layout.derivatives_description(), {{"Name", scene.name + " ground truth"},
                                                 {"BIDSVersion", "1.9.0"},
                                                 {"DatasetType", "derivative"},
                                                 {"GeneratedBy", generated_by()}});
  writer.text(layout.dseg_table(), dseg_table(scene));
  writer.text(layout.scene_copy(), scene.source_text);
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed}) {
    std::filesystem::create_directories(layout.anat_image(state, "T1w").parent_path());
  }

  std::string log;
  for (const auto& line : reporter.log_lines())
    log += line + "\n";
  writer.text(layout.log(), log);

  nlohmann::json stages = nlohmann::json::array();
  for (const auto& stage : summary.stages)
    stages.push_back(stage_json(stage));
  nlohmann::json files = nlohmann::json::array();
  for (const auto& file : writer.files())
    files.push_back(file.generic_string());
  writer.json(layout.provenance(),
              {{"phantasm_version", version},
               {"scene", {{"file", scene.file.filename().string()}, {"sha256", scene.sha256}}},
               {"seed", scene.seed},
               {"settings", scene_settings_json(scene)},
               {"stages", stages},
               {"files", files}});
  summary.files = writer.files();
  return summary;
}

} // namespace phantasm
