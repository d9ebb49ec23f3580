// Time of the MR image stage for three contrasts (MPRAGE T1w, spin-echo T2w, FLAIR) on a 256^3
// grid of nested ellipsoids (CSF, grey and white matter, with partial-volume fractions), with
// and without the k-space acquisition and with a ring of coils. OMP_NUM_THREADS sets the threads.
// The k-space cases run through the pipeline and through the former per-coil acquisition
// (reference::acquire_in_kspace, mri/kspace_reference.hpp) alternately, ROUNDS times, in one
// process, and report each round's time, the median, the median processor time (user and system, all
// threads), a hash of the images' bytes (the last round's; the same hash from two builds means
// the same images), and the largest difference between the two methods' noise-free images
// (relative to the brightest voxel).
// Usage: mri_images [SIZE [ROUNDS [COMPARE [CASES [METHODS]]]]]   (SIZE voxels per axis, 256 by
// default; ROUNDS 1 by default; COMPARE 0 skips the noise-free comparison, which runs each k-space
// case twice more; CASES the letters of the cases to run, d (sampled directly), k (k-space, one
// coil) and c (k-space, 8 coils), all by default; METHODS pipeline, per_coil or both, both by
// default, e.g. `mri_images 256 3 0 c pipeline` times the 8-coil pipeline alone)

#include "mri/kspace_reference.hpp"
#include "mri/synthesize_images.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <sys/resource.h>

using namespace phantasm;

namespace {

/// Nested ellipsoids: each tissue's fraction from the signed distance to its shell (a linear ramp
/// over one voxel), outer tissues minus the inner ones.
VoxelizedPhantom nested_ellipsoids(int size) {
  VoxelizedPhantom v;
  v.grid.dims = Eigen::Vector3i::Constant(size);
  v.grid.spacing_mm = Eigen::Vector3d::Constant(256.0 / size);
  v.grid.world_from_voxel.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * (256.0 / size);
  v.tissues = {"csf", "grey_matter", "white_matter"};
  const auto count = static_cast<std::size_t>(v.grid.voxel_count());
  // Every tissue's fractions, then the background's; the label (tissue + 1) of the largest.
  std::vector<std::vector<float>> fractions(4, std::vector<float>(count, 0.0f));
  std::vector<std::int32_t> labels(count, 0);
  const double radii[3][3] = {{75, 90, 80}, {70, 85, 75}, {50, 65, 55}};
  for (int k = 0, n = 0; k < size; ++k)
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i, ++n) {
        const Eigen::Vector3d x =
            (Eigen::Vector3d(i, j, k) - Eigen::Vector3d::Constant(0.5 * (size - 1))) * (256.0 / size);
        double inside[3];
        for (int t = 0; t < 3; ++t) {
          const double r = std::sqrt(std::pow(x.x() / radii[t][0], 2) + std::pow(x.y() / radii[t][1], 2) +
                                     std::pow(x.z() / radii[t][2], 2));
          const double distance_mm = (r - 1.0) * radii[t][0];
          inside[t] = std::clamp(0.5 - distance_mm / (256.0 / size), 0.0, 1.0);
        }
        const auto u = static_cast<std::size_t>(n);
        fractions[0][u] = static_cast<float>(inside[0] - inside[1]);
        fractions[1][u] = static_cast<float>(inside[1] - inside[2]);
        fractions[2][u] = static_cast<float>(inside[2]);
        fractions[3][u] = static_cast<float>(1.0 - inside[0]);
        std::size_t largest = 3; // the background
        for (std::size_t t = 0; t < 3; ++t)
          if (fractions[t][u] > fractions[largest][u]) largest = t;
        labels[u] = largest == 3 ? 0 : static_cast<std::int32_t>(largest) + 1;
      }
  v.reference = compact_tissue_volumes(std::move(labels), {-1, 0, 1, 2}, fractions);
  return v;
}

OrganTable three_organs() {
  std::vector<OrganNesting> organs;
  for (const char* tissue : {"csf", "grey_matter", "white_matter"})
    organs.push_back({tissue, tissue, ""});
  return OrganTable(organs);
}

MriSettings three_contrasts() {
  MriSettings scene;
  scene.seed = 1;
  scene.field_strength_T = 3.0;
  SequenceSettings t1;
  t1.name = "T1w";
  t1.kind = SequenceKind::mprage;
  t1.TR_ms = 2300;
  t1.TI_ms = 900;
  t1.TE_ms = 2.98;
  t1.flip_deg = 9;
  t1.echo_spacing_ms = 7.1;
  t1.turbo_factor = 176;
  SequenceSettings t2;
  t2.name = "T2w";
  t2.kind = SequenceKind::spin_echo;
  t2.TR_ms = 4000;
  t2.TE_ms = 100;
  SequenceSettings flair;
  flair.name = "FLAIR";
  flair.kind = SequenceKind::inversion_recovery;
  flair.readout = Readout::spin_echo;
  flair.TR_ms = 9000;
  flair.TI_ms = 2500;
  flair.TE_ms = 120;
  scene.sequences = {t1, t2, flair};
  scene.acquisition.noise_percent = 3;
  scene.acquisition.bias_percent = 20;
  scene.parameter_maps = false;
  return scene;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// User and system time of the process so far, all threads.
double process_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// FNV-1a of the bytes of every image: equal hashes across builds mean the same images.
std::uint64_t bytes_hash(const MrImages& images) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const MrImage& image : images.reference) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(image.magnitude.data());
    for (std::size_t b = 0; b < image.magnitude.size() * sizeof(float); ++b)
      hash = (hash ^ bytes[b]) * 0x100000001b3ULL;
  }
  return hash;
}

struct Case {
  const char* name;
  bool kspace;
  int coils;
  char letter; ///< selects the case on the command line
};

MriSettings scene_of(const Case& c, int size, double noise_percent) {
  MriSettings scene = three_contrasts();
  scene.acquisition.kspace = c.kspace;
  scene.acquisition.acquired_voxel_mm = Eigen::Vector3d::Constant(1.25 * 256.0 / size);
  scene.acquisition.coils = c.coils;
  scene.acquisition.noise_percent = noise_percent;
  return scene;
}

} // namespace

int main(int argc, char** argv) {
  const int size = argc > 1 ? std::atoi(argv[1]) : 256;
  const int rounds = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
  const bool compare = argc > 3 ? std::atoi(argv[3]) != 0 : true;
  const std::string cases = argc > 4 ? argv[4] : "dkc";
  const std::string methods_wanted = argc > 5 ? argv[5] : "both";
  if (methods_wanted != "both" && methods_wanted != "pipeline" && methods_wanted != "per_coil") {
    std::fprintf(stderr, "METHODS: pipeline, per_coil or both\n");
    return 2;
  }
  const VoxelizedPhantom volumes = nested_ellipsoids(size);
  std::printf("%d^3 grid, three contrasts, noise 3 %%, bias 20 %%, %d threads, %d rounds\n", size,
              omp_get_max_threads(), rounds);
  Reporter quiet = Reporter::silent();
  auto run = [&](const MriSettings& scene, CoilAcquisition method, double& seconds, double& cpu) {
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = process_cpu_seconds();
    MrImages images = synthesize_images(scene, three_organs(), volumes, report, quiet, method);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    cpu = process_cpu_seconds() - cpu_start;
    return images;
  };
  for (const Case& c :
       {Case{"sampled directly", false, 1, 'd'}, Case{"k-space (acquired 1.25x coarser)", true, 1, 'k'},
        Case{"k-space, 8 coils", true, 8, 'c'}}) {
    if (cases.find(c.letter) == std::string::npos) continue;
    const MriSettings scene = scene_of(c, size, 3.0);
    const int methods = c.kspace ? 2 : 1;
    // Without k-space there is one method (it runs as "pipeline").
    auto wanted = [&](int m) {
      return !c.kspace || methods_wanted == "both" || methods_wanted == (m == 0 ? "pipeline" : "per_coil");
    };
    std::vector<double> times[2], cpu_times[2];
    std::uint64_t hashes[2] = {0, 0};
    for (int round = 0; round < rounds; ++round)
      for (int m = 0; m < methods; ++m) {
        // Alternate which method goes first, so that neither always meets a warm or cold machine.
        const int which = (m + round) % methods;
        if (!wanted(which)) continue;
        double seconds = 0.0, cpu = 0.0;
        const MrImages images =
            run(scene, which == 0 ? nullptr : &reference::acquire_in_kspace, seconds, cpu);
        times[which].push_back(seconds);
        cpu_times[which].push_back(cpu);
        hashes[which] = bytes_hash(images);
      }
    for (int m = 0; m < methods; ++m) {
      if (!wanted(m)) continue;
      std::string each;
      for (double t : times[m])
        each += " " + std::to_string(t).substr(0, 5);
      const char* method = !c.kspace ? "" : m == 0 ? ", pipeline" : ", per coil (former)";
      std::printf("%-46s median %6.2f s  (rounds:%s)  processor %.2f s  bytes %016llx\n",
                  (std::string(c.name) + method).c_str(), median(times[m]), each.c_str(),
                  median(cpu_times[m]), static_cast<unsigned long long>(hashes[m]));
    }
    if (c.kspace && compare && methods_wanted == "both") {
      // The methods differ in their noise deviates; without noise they must agree to rounding.
      const MriSettings clean = scene_of(c, size, 0.0);
      double unused = 0.0, unused_cpu = 0.0;
      const MrImages a = run(clean, nullptr, unused, unused_cpu);
      const MrImages b = run(clean, &reference::acquire_in_kspace, unused, unused_cpu);
      double worst = 0.0, brightest = 0.0;
      for (std::size_t q = 0; q < a.reference.size(); ++q)
        for (std::size_t v = 0; v < a.reference[q].magnitude.size(); ++v) {
          worst =
              std::max(worst, std::abs(double(a.reference[q].magnitude[v]) - b.reference[q].magnitude[v]));
          brightest = std::max(brightest, double(b.reference[q].magnitude[v]));
        }
      std::printf("%-46s %.2e of the brightest voxel\n", "  noise-free images, largest difference",
                  worst / brightest);
    }
  }
  return 0;
}
