#include "apps/phantasm/commands.hpp"
#include "io/atomic_file.hpp"
#include "io/hdf5_export.hpp"
#include "io/nifti_file.hpp"
#include "io/output_path.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_hdf5_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, output;
    int compression = 4, chunk = 64;
    bool quiet = false;
    int write_delay_ms = 0, read_delay_ms = 0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "hdf5",
      "Export a dataset's images, labels, fractions, parameter maps, fields, exact masks, Jacobian and "
      "landmarks into one HDF5 file (docs/use-with-your-tools.md)");
  command->add_option("dataset", options->dataset, "Dataset folder written by phantasm run or batch")
      ->required();
  command->add_option("-o,--output", options->output, "HDF5 file to write")->required();
  command->add_option("--compression", options->compression, "gzip level")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  command->add_option("--chunk", options->chunk, "Chunk edge in voxels")
      ->check(CLI::Range(8, 1024))
      ->capture_default_str();
  command->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  // For tests that interrupt an export while it reads or writes; hidden from --help.
  command->add_option("--write-delay-ms", options->write_delay_ms)->group("")->check(CLI::NonNegativeNumber);
  command->add_option("--read-delay-ms", options->read_delay_ms)->group("")->check(CLI::NonNegativeNumber);
  command->callback([options, &action] {
    action = [options] {
      set_write_delay_for_testing(options->write_delay_ms);
      set_read_delay_for_testing(options->read_delay_ms);
      require_replaceable_file(options->output, "--output");
      const Hdf5ExportSummary summary = export_hdf5(options->dataset, options->output,
                                                    Hdf5ExportOptions{options->compression, options->chunk},
                                                    [&](const std::string& subject) {
                                                      if (!options->quiet)
                                                        std::cerr << "[hdf5] " << subject << "\n";
                                                    });
      if (!options->quiet) {
        std::cerr << "[hdf5] wrote " << summary.arrays << " arrays of " << summary.subjects << " subjects to "
                  << options->output << "\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
