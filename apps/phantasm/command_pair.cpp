#include "apps/phantasm/commands.hpp"
#include "evaluation/subject_pairs.hpp"

#include <cstdio>
#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_pair_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, out, pairs = "all";
    std::size_t random = 0;
    std::uint64_t seed = 0;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "pair", "Fields between subjects of one template (a population sweep), composed through it, with "
              "their exact masks and both subjects' landmarks");
  command->add_option("dataset", options->dataset, "Dataset folder written by phantasm batch")->required();
  command->add_option("-o,--output", options->out, "Folder to make (new or empty)")->required();
  auto* pairs = command->add_option("--pairs", options->pairs,
                                    "all (default) or subject pairs such as 01:02,03:05 (both directions)");
  auto* random =
      command->add_option("--random", options->random, "This many distinct pairs drawn with --seed instead")
          ->check(CLI::PositiveNumber);
  command->add_option("--seed", options->seed, "Seed of --random (default 0)")->needs(random);
  random->excludes(pairs);
  command->add_flag("-q,--quiet", options->quiet, "Do not print the pairs");
  command->callback([options, &action] {
    action = [options] {
      PairRequest request;
      request.dataset = options->dataset;
      request.out = options->out;
      request.random_count = options->random;
      request.seed = options->seed;
      if (options->pairs != "all") request.listed = parse_pair_list(options->pairs);
      const nlohmann::json written = write_subject_pairs(request);
      if (!options->quiet) {
        for (const auto& pair : written["pairs"]) {
          std::printf("  sub-%s -> sub-%s  %s  (exact in %.1f %% of the grid; %zu voxels left out by the "
                      "round trip)\n",
                      pair["moving"].get<std::string>().c_str(), pair["fixed"].get<std::string>().c_str(),
                      pair["folder"].get<std::string>().c_str(), 100.0 * pair["exact_fraction"].get<double>(),
                      pair["left_out_by_round_trip"].get<std::size_t>());
        }
        std::cout << written["pairs"].size() << " fields written into " << options->out << "\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
