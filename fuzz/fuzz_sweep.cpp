// libFuzzer target: sweep files (docs/batch.md), as `phantasm validate` and `batch` read them.
// The input is the sweep file; its base scenes are the test scenes (`../scenes/small-head.yaml`)
// and the shipped head (`head.yaml`), copied beside it. load_sweep may refuse a sweep with
// InputError only. Every subject is made and checked when the sweep has a few (a large sweep's
// scenes are the same code run many times; its labels are still made).
#include "batch/sweep.hpp"
#include "fuzz/fuzz_support.hpp"

#include <cstdint>
#include <string>

using namespace phantasm;

namespace {

/// The sweep's path, with the base scenes the seeds name beside it (made once per process).
const std::filesystem::path& sweep_path() {
  static const std::filesystem::path path = [] {
    namespace fs = std::filesystem;
    const fs::path source(PHANTASM_SOURCE_DIR);
    const fs::path root = fuzz::scratch_folder();
    fs::create_directories(root / "sweeps");
    fs::create_directories(root / "scenes");
    for (const auto& entry : fs::directory_iterator(source / "tests" / "data" / "scenes"))
      fs::copy_file(entry.path(), root / "scenes" / entry.path().filename());
    fs::copy_file(source / "data-synthetic" / "head.yaml", root / "sweeps" / "head.yaml");
    return root / "sweeps" / "sweep.yaml";
  }();
  return path;
}

/// Sweeps of at most this many subjects are made in full.
constexpr std::size_t k_full_sweep = 8;

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path& path = sweep_path();
  fuzz::write_scratch_file("sweeps/sweep.yaml", data, size);
  fuzz::expect_input_errors_only("load_sweep", [&] {
    (void)is_sweep_file(path);
    const Sweep labels = load_sweep(path, SweepDepth::labels);
    if (labels.subjects.size() != labels.subject_count)
      fuzz::finding("load_sweep (labels) made " + std::to_string(labels.subjects.size()) + " of " +
                    std::to_string(labels.subject_count) + " subjects");
    if (labels.subject_count > k_full_sweep) return;
    const Sweep sweep = load_sweep(path, SweepDepth::full);
    if (sweep.subjects.size() != labels.subject_count)
      fuzz::finding("load_sweep (full) made " + std::to_string(sweep.subjects.size()) + " subjects, labels " +
                    std::to_string(labels.subject_count));
    for (std::size_t s = 0; s < sweep.subjects.size(); ++s)
      if (sweep.subjects[s].id != labels.subjects[s].id)
        fuzz::finding("subject " + std::to_string(s) + " is " + sweep.subjects[s].id + " in full and " +
                      labels.subjects[s].id + " in labels");
    (void)participants_tsv(sweep);
  });
  return 0;
}
