#include "apps/phantasm/commands.hpp"
#include "atlas/colin27_head.hpp"
#include "io/atomic_file.hpp"
#include "io/nifti_file.hpp"
#include "io/output_path.hpp"

#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

namespace phantasm::cli {
namespace {

/// "labels.nii.gz" -> "labels.tsv": the label table sits next to the volume.
std::filesystem::path table_path(const std::filesystem::path& volume) {
  std::string name = volume.filename().string();
  for (const char* suffix : {".nii.gz", ".nii"}) {
    const std::string s = suffix;
    if (name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
      break;
    }
  }
  return volume.parent_path() / (name + ".tsv");
}

} // namespace

void add_atlas_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string output, templates = default_colin27_templates_dir().string();
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* atlas = app.add_subcommand("atlas", "Write labelled anatomy derived from published atlases");
  atlas->require_subcommand(1);
  // The atlases are nested subcommands of "atlas", named through a constant: the top-level
  // command list (phantasm --help, and its test) holds "atlas" alone.
  const std::string colin27_name = "colin27";
  CLI::App* colin = atlas->add_subcommand(
      colin27_name,
      "Label the Colin 27 head (scalp, skull, CSF, grey and white matter, ventricles, deep nuclei, "
      "cerebellum, brainstem) on its 1 mm grid; see docs/anatomy-colin27.md");
  colin
      ->add_option("-o,--output", options->output,
                   "NIfTI label volume to write (.nii or .nii.gz); the label "
                   "table goes next to it as .tsv")
      ->required();
  colin
      ->add_option("--templates", options->templates,
                   "Folder with ch2.nii.gz, ch2bet.nii.gz and aal.nii.gz (Debian package mricron-data)")
      ->capture_default_str();
  colin->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  colin->callback([options, &action] {
    action = [options] {
      const auto start = std::chrono::steady_clock::now();
      // Before the minutes of deriving the labels: a target that cannot be written is refused now.
      require_replaceable_file(options->output, "--output");
      require_replaceable_file(table_path(options->output), "--output");
      const HeadLabels head = derive_colin27_head(options->templates, Colin27Options{});
      NiftiWriteOptions write_options;
      write_options.intent = NiftiIntent::label;
      write_options.description = "phantasm colin27 head labels";
      write_nifti_labels(options->output, head.grid, head.labels, write_options);
      const std::vector<double> volumes = label_volumes_ml(head);
      std::ostringstream table;
      table << "label\tname\ttissue\tvolume_ml\n" << std::fixed << std::setprecision(3);
      for (const HeadLabelInfo& info : head.table) {
        table << info.label << '\t' << info.name << '\t' << info.tissue << '\t'
              << (info.label < static_cast<std::int32_t>(volumes.size()) ? volumes[info.label] : 0.0) << '\n';
      }
      const std::filesystem::path tsv = table_path(options->output);
      write_file_atomically(tsv, table.str());
      if (!options->quiet) {
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::cerr << "[atlas] wrote " << options->output << " and " << tsv.string() << " in " << std::fixed
                  << std::setprecision(1) << seconds << " s\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
