#include "mri/synthesize_images.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "mri/kspace.hpp"
#include "mri/parameter_maps.hpp"
#include "mri/receive_coils.hpp"
#include "mri/signal_equations.hpp"
#include "mri/texture_signal.hpp"
#include "mri/tissue_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <random>
#include <stdexcept>

namespace phantasm {
namespace {

/// Complex Gaussian noise of std sigma on each part of every voxel, drawn per line along i from
/// streams seeded by `seed`, so the result does not depend on the number of threads.
void add_image_noise(std::vector<std::complex<double>>& image, const Eigen::Vector3i& dims, double sigma,
                     std::uint64_t seed) {
  const std::int64_t lines = std::int64_t{dims.y()} * dims.z();
#pragma omp parallel for schedule(static)
  for (std::int64_t line = 0; line < lines; ++line) {
    std::mt19937_64 random(mix_seed(seed, static_cast<std::uint64_t>(line)));
    std::normal_distribution<double> noise(0.0, sigma);
    std::complex<double>* row = image.data() + line * dims.x();
    for (int i = 0; i < dims.x(); ++i) {
      const double re = noise(random), im = noise(random);
      row[i] += std::complex<double>(re, im);
    }
  }
}

/// for_each_voxel() over layer k of the grid, handing `visit` each voxel's (i, j) as well:
/// followed along from voxel to voxel (for_each_voxel() visits them in order), not divided out.
template <class Visit>
void for_each_voxel_of_layer(const TissueVolumes& volumes, const Eigen::Vector3i& dims, int k,
                             Visit&& visit) {
  const int nx = dims.x();
  const auto layer = static_cast<std::size_t>(nx) * static_cast<std::size_t>(dims.y());
  const std::size_t first = static_cast<std::size_t>(k) * layer;
  std::size_t next = first;
  int i = 0, j = 0;
  volumes.for_each_voxel(first, first + layer, [&](std::size_t v, const float* fractions) {
    if (v != next) { // not the next one after all: find it
      const std::size_t in_layer = v - first;
      i = static_cast<int>(in_layer % static_cast<std::size_t>(nx));
      j = static_cast<int>(in_layer / static_cast<std::size_t>(nx));
    }
    visit(v, i, j, fractions);
    next = v + 1;
    if (++i == nx) {
      i = 0;
      ++j;
    }
  });
}

/// A linear ramp along a seeded direction spanning 1 -/+ bias_percent / 200 over the object,
/// evaluated where it is needed rather than stored: a volume of doubles less to fault in, write
/// and read back for every image.
class BiasField {
public:
  BiasField(double bias_percent, std::mt19937_64& random, const ImageGrid& grid,
            const TissueVolumes& volumes) {
    if (bias_percent <= 0.0) return;
    std::normal_distribution<double> normal;
    Eigen::Vector3d direction(normal(random), normal(random), normal(random));
    direction.normalize();
    // The position along the direction is affine in the voxel index: a . (i, j, k) + offset.
    m_a = grid.world_from_voxel.topLeftCorner<3, 3>().transpose() * direction;
    m_offset = direction.dot(grid.world_from_voxel.topRightCorner<3, 1>());
    const int nz = grid.dims.z();
    const std::size_t background = volumes.fractions_per_voxel() - 1;
    const Eigen::Vector3d a = m_a;
    const double offset = m_offset;
    double low = std::numeric_limits<double>::infinity(), high = -low;
#pragma omp parallel for reduction(min : low) reduction(max : high) schedule(dynamic, 1)
    for (int k = 0; k < nz; ++k)
      for_each_voxel_of_layer(volumes, grid.dims, k, [&](std::size_t, int i, int j, const float* fractions) {
        if (fractions[background] >= 0.5f) return;
        const double along = a.x() * i + a.y() * j + a.z() * k + offset;
        low = std::min(low, along);
        high = std::max(high, along);
      });
    if (high > low) {
      m_varies = true;
      m_half_span = bias_percent / 200.0;
      m_low = low;
      m_high = high;
    }
  }

  /// False when the field is 1 everywhere.
  bool varies() const {
    return m_varies;
  }
  /// The field along row (j, k), n voxels, when it varies.
  void row(int j, int k, int n, double* field) const {
    for (int i = 0; i < n; ++i) {
      const double along = m_a.x() * i + m_a.y() * j + m_a.z() * k + m_offset;
      field[i] = 1.0 + m_half_span * (2.0 * (along - m_low) / (m_high - m_low) - 1.0);
    }
  }

private:
  bool m_varies = false;
  Eigen::Vector3d m_a = Eigen::Vector3d::Zero();
  double m_offset = 0.0, m_half_span = 0.0, m_low = 0.0, m_high = 0.0;
};

/// What stays the same for every image of a run: the grid, the coils and the k-space sampling.
struct Acquisition {
  const ImageGrid& grid;
  const ReceiveCoils& coils;
  std::optional<KspaceSampling> kspace;
  double bias_percent;
  KspacePipeline* pipeline; ///< k-space through the pipeline; nullptr: per coil (or no k-space)
  CoilAcquisition per_coil; ///< k-space per coil (without the pipeline)
};

/// Voxel buffers that every image of a run reuses: fresh ones of hundreds of megabytes per
/// image cost their page faults and zeroing again each time.
struct Workspace {
  std::vector<double> object, energy; ///< the object (not through the pipeline), the sum of squares
  std::vector<float> object_float;    ///< the object for the pipeline, in its precision
};

/// Writes the object of every voxel of layer k, the fraction-weighted signed signals (partial
/// volume may cancel at a null) times the bias field, converted to Value.
/// With a texture, a textured tissue's signal is the one at the voxel's T1 and PD factors.
template <class Value>
void object_layer(const TissueVolumes& volumes, const std::vector<double>& tissue_signal,
                  const BiasField& bias, const Eigen::Vector3i& dims, int k, Value* object,
                  const TexturedSignal* texture) {
  // The field one row at a time (a loop the compiler vectorizes), 1 where it does not vary.
  std::vector<double> field(static_cast<std::size_t>(dims.x()), 1.0);
  int field_row = -1;
  for_each_voxel_of_layer(volumes, dims, k, [&](std::size_t v, int i, int j, const float* fractions) {
    if (bias.varies() && j != field_row) {
      bias.row(j, k, dims.x(), field.data());
      field_row = j;
    }
    double sum = 0.0;
    if (texture) {
      const float t1 = texture->maps().T1_factor[v], pd = texture->maps().PD_factor[v];
      for (std::size_t t = 0; t < tissue_signal.size(); ++t)
        if (fractions[t] != 0.0f)
          sum += fractions[t] * (texture->textured(t) ? texture->signal(t, t1, pd) : tissue_signal[t]);
    } else {
      for (std::size_t t = 0; t < tissue_signal.size(); ++t)
        sum += fractions[t] * tissue_signal[t];
    }
    object[v] = static_cast<Value>(sum * field[static_cast<std::size_t>(i)]);
  });
}

MrImage image_of(const Acquisition& acquisition, Workspace& workspace, const SequenceSettings& sequence,
                 std::uint64_t seed, const TissueVolumes& volumes, const std::vector<double>& tissue_signal,
                 double noise_sigma, const TexturedSignal* texture) {
  const ImageGrid& grid = acquisition.grid;
  MrImage image;
  image.sequence = &sequence;
  image.noise_sigma = noise_sigma;
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  std::mt19937_64 random(seed);
  const BiasField bias(acquisition.bias_percent, random, grid, volumes);
  const auto voxels = static_cast<std::int64_t>(count);
  const int layers = grid.dims.z();
  const int coils = acquisition.coils.count();
  image.magnitude.resize(count);
  if (acquisition.pipeline) {
    // The object in single precision, the precision of the pipeline's transforms.
    std::vector<float>& object = workspace.object_float;
    object.resize(count);
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < layers; ++k)
      object_layer(volumes, tissue_signal, bias, grid.dims, k, object.data(), texture);
    KspacePipeline& pipeline = *acquisition.pipeline;
    pipeline.set_object(object.data());
    // The sum of squares (one coil: the squared magnitude) over the coils, a group of coils at a
    // time: the first group starts the sum, the last writes its root; the sum is stored between
    // groups only.
    const int together = pipeline.coils_together();
    std::vector<double>& energy = workspace.energy;
    if (coils > together) energy.resize(count);
    for (int first = 0; first < coils; first += together) {
      throw_if_cancelled();
      const int last = std::min(coils, first + together);
      if (coils > 1 && progress_detail_due())
        progress_detail("coil " + std::to_string(first + 1) +
                        (last > first + 1 ? "-" + std::to_string(last) : "") + "/" + std::to_string(coils));
      std::vector<KspaceCoil> group;
      for (int c = first; c < last; ++c)
        group.push_back({acquisition.coils.sensitivity_plane(c), noise_sigma,
                         mix_seed(seed, static_cast<std::uint64_t>(c) + 1)});
      pipeline.add_squared_magnitude(group.data(), last - first, first == 0,
                                     coils > together ? energy.data() : nullptr,
                                     last == coils ? image.magnitude.data() : nullptr);
    }
    return image;
  }

  std::vector<double>& object = workspace.object;
  object.resize(count);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < layers; ++k)
    object_layer(volumes, tissue_signal, bias, grid.dims, k, object.data(), texture);
  const int nx = grid.dims.x(), ny = grid.dims.y();
  const std::int64_t rows = std::int64_t{ny} * grid.dims.z();
  std::vector<double> sum_of_squares(coils > 1 ? count : 0, 0.0);
  std::vector<std::complex<double>> coil_image(count);
  for (int c = 0; c < coils; ++c) {
    throw_if_cancelled();
    if (coils > 1 && progress_detail_due())
      progress_detail("coil " + std::to_string(c + 1) + "/" + std::to_string(coils));
#pragma omp parallel for schedule(static)
    for (std::int64_t row = 0; row < rows; ++row) {
      const int j = static_cast<int>(row % ny);
      for (int i = 0; i < nx; ++i) {
        const auto v = static_cast<std::size_t>(row * nx + i);
        coil_image[v] = acquisition.coils.sensitivity(c, i, j) * object[v];
      }
    }
    const std::uint64_t coil_seed = mix_seed(seed, static_cast<std::uint64_t>(c) + 1);
    if (acquisition.kspace) {
      acquisition.per_coil(coil_image, *acquisition.kspace, noise_sigma, coil_seed);
    } else if (noise_sigma > 0.0) {
      add_image_noise(coil_image, grid.dims, noise_sigma, coil_seed);
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t n = 0; n < voxels; ++n) {
      const auto v = static_cast<std::size_t>(n);
      if (coils == 1) {
        image.magnitude[v] = static_cast<float>(std::abs(coil_image[v]));
      } else {
        sum_of_squares[v] += std::norm(coil_image[v]);
        if (c + 1 == coils) image.magnitude[v] = static_cast<float>(std::sqrt(sum_of_squares[v]));
      }
    }
  }
  return image;
}

/// The k-space sampling the scene asks for, or nothing when images are sampled directly.
std::optional<KspaceSampling> kspace_sampling(const AcquisitionSettings& a, const ImageGrid& grid) {
  if (!a.kspace) return std::nullopt;
  KspaceSampling sampling;
  sampling.dims = grid.dims;
  for (int axis = 0; axis < 3; ++axis) {
    const double acquired = a.acquired_voxel_mm
                                ? grid.dims[axis] * grid.spacing_mm[axis] / (*a.acquired_voxel_mm)[axis]
                                : static_cast<double>(grid.dims[axis]) / a.kspace_oversampling;
    sampling.acquired[axis] = std::clamp(static_cast<int>(std::lround(acquired)), 1, grid.dims[axis]);
  }
  sampling.slice_thickness_voxels = a.slice_thickness_mm / grid.spacing_mm.z();
  return sampling;
}

using TissueParameterTable = std::map<std::string, TissueParameters>;

Relaxation relaxation_of(const TissueParameterTable& parameters, const std::string& tissue) {
  return relaxation_of(parameters.at(tissue));
}

/// Refuses reference images of other settings or another grid.
void check_given(const ReferenceImages& given, const MriSettings& mri, const VoxelizedPhantom& volumes) {
  bool matches = given.images.size() == mri.sequences.size() && given.maps.has_value() == mri.parameter_maps;
  for (const MrImage& image : given.images)
    matches = matches && image.magnitude.size() == volumes.reference.labels.size();
  if (!matches)
    throw std::invalid_argument("synthesize_images: reference images of other settings or another grid");
}

/// The report's lines on the acquisition: k-space sampling and receive coils.
void report_acquisition(const Acquisition& acquisition, const AcquisitionSettings& settings,
                        StageReport& report) {
  const ImageGrid& grid = acquisition.grid;
  if (acquisition.kspace) {
    const KspaceSampling& k = *acquisition.kspace;
    std::string line = "k-space: object " + std::to_string(k.dims.x()) + "x" + std::to_string(k.dims.y()) +
                       "x" + std::to_string(k.dims.z()) + ", acquired matrix " +
                       std::to_string(k.acquired.x()) + "x" + std::to_string(k.acquired.y()) + "x" +
                       std::to_string(k.acquired.z()) + " (voxel " +
                       format_number(k.dims.x() * grid.spacing_mm.x() / k.acquired.x()) + " x " +
                       format_number(k.dims.y() * grid.spacing_mm.y() / k.acquired.y()) + " x " +
                       format_number(k.dims.z() * grid.spacing_mm.z() / k.acquired.z()) +
                       " mm), unfiltered truncation (Gibbs ringing), zero-filled onto the grid";
    if (k.slice_thickness_voxels > 0.0)
      line += ", rectangular slice profile " + format_number(settings.slice_thickness_mm) + " mm along k";
    report.modelled.push_back(line + "; noise added in k-space");
  } else if (settings.acquired_voxel_mm || settings.slice_thickness_mm > 0.0) {
    report.skipped.push_back("acquired voxel size and slice thickness: they act in k-space, and "
                             "acquisition.kspace is false");
  }
  if (acquisition.coils.count() > 1) {
    report.modelled.push_back(
        std::to_string(acquisition.coils.count()) +
        " receive coils on a ring (sensitivity ~ 1/distance), noise per coil, sum of squares");
  }
}

/// Sequence q's signal of each tissue (x PD units), reported; refuses a signal that is not finite.
std::vector<double> tissue_signals(const SequenceSettings& sequence, std::size_t q,
                                   const std::vector<std::string>& tissues,
                                   const TissueParameterTable& parameters, StageReport& report) {
  std::vector<double> tissue_signal;
  std::string line = sequence.name + " tissue signals (x PD units):";
  for (const std::string& tissue : tissues) {
    const Relaxation r = relaxation_of(parameters, tissue);
    tissue_signal.push_back(sequence_signal(sequence, r));
    // Relaxation times beyond any tissue's with an excitation of 0 make the signal equations
    // 0/0: an image of NaN must not be written (the run stops before any file is).
    if (!std::isfinite(tissue_signal.back())) {
      throw SettingError(
          "sequences[" + std::to_string(q) + "].type",
          "sequence " + sequence.name + ", tissue " + tissue + ": expected a finite signal, found " +
              (std::isnan(tissue_signal.back()) ? std::string("NaN") : format_number(tissue_signal.back())) +
              " (T1 " + format_number(r.T1_ms) + " ms, T2 " + format_number(r.T2_ms) + " ms, T2* " +
              format_number(r.T2star_ms) + " ms, PD " + format_number(r.PD) + "; TR " +
              format_number(sequence.TR_ms) + " ms, TE " + format_number(sequence.TE_ms) + " ms, flip " +
              format_number(sequence.flip_deg) + " deg)");
    }
    line += " " + tissue + " " + format_number(tissue_signal.back());
  }
  report.modelled.push_back(line);
  return tissue_signal;
}

/// A sequence's receiver gain and the noise's sigma in scanner units.
struct ReceiverLevels {
  double gain = 1.0, sigma = 0.0;
};

/// The receiver gain: the scene's, or the one that puts the reference tissue at the scanner's
/// level; and the noise's sigma (a percentage of the reference tissue's signal), reported.
ReceiverLevels receiver_levels(const SequenceSettings& sequence, const AcquisitionSettings& settings,
                               const TissueParameterTable& parameters,
                               const std::vector<double>& tissue_signal, StageReport& report) {
  double reference_signal = 0.0;
  const std::string& reference_tissue = settings.noise_reference_tissue;
  if (parameters.count(reference_tissue)) {
    reference_signal = sequence_signal(sequence, relaxation_of(parameters, reference_tissue));
  } else if (settings.noise_percent > 0.0) {
    report.skipped.push_back("noise of " + sequence.name + ": the reference tissue " + reference_tissue +
                             " is not in the phantom");
  }
  double brightest = 0.0;
  for (double signal : tissue_signal)
    brightest = std::max(brightest, std::abs(signal));
  const double gain =
      settings.receiver_gain ? *settings.receiver_gain : automatic_receiver_gain(reference_signal, brightest);
  std::string rule = " (the scene's)";
  if (!settings.receiver_gain)
    rule = std::abs(std::abs(reference_signal) * gain - k_receiver_reference_level) <
                   1e-6 * k_receiver_reference_level
               ? " (automatic: " + reference_tissue + " at " + format_number(k_receiver_reference_level) + ")"
               : " (automatic: the brightest tissue at " + format_number(brightest * gain) + ")";
  report.modelled.push_back(sequence.name + " receiver gain " + format_number(gain) + rule);
  return {gain, settings.noise_percent / 100.0 * std::abs(reference_signal) * gain};
}

/// The parameter maps of both states (the given reference's, when given), textured where the
/// phantom has texture.
void add_parameter_maps(const VoxelizedPhantom& volumes, const TissueVolumes* deformed,
                        const TissueParameterTable& parameters, std::optional<ReferenceImages>& given,
                        MrImages& images, StageReport& report) {
  images.reference_maps =
      given ? std::move(given->maps) : parameter_maps(volumes.reference, volumes.tissues, parameters);
  if (deformed) images.deformed_maps = parameter_maps(*deformed, volumes.tissues, parameters);
  if (volumes.reference_texture && !given)
    apply_texture(*images.reference_maps, volumes.reference, volumes.tissues, parameters,
                  *volumes.reference_texture);
  if (deformed && volumes.deformed_texture)
    apply_texture(*images.deformed_maps, *deformed, volumes.tissues, parameters, *volumes.deformed_texture);
  if (volumes.reference_texture)
    report.modelled.push_back("texture in the parameter maps and images: " +
                              volumes.reference_texture->description);
  report.modelled.push_back("parameter maps PD, T1, T2, T2* (fraction-weighted; PD summed, times averaged)");
}

/// The receive coils' object mask: the voxels that are mostly object in the reference state.
std::vector<bool> object_mask(const TissueVolumes& reference) {
  std::vector<bool> mask(reference.labels.size());
  const std::size_t background = reference.fractions_per_voxel() - 1;
  reference.for_each_voxel(
      0, mask.size(), [&](std::size_t v, const float* fractions) { mask[v] = fractions[background] < 0.5f; });
  return mask;
}

} // namespace

MrImages synthesize_images(const MriSettings& mri, const OrganTable& organs, const VoxelizedPhantom& volumes,
                           StageReport& report, Reporter& reporter, SynthesisOptions options) {
  MrImages images;
  // The states to make: the reference unless given, the deformed one unless passed over.
  std::optional<ReferenceImages>& given = options.reference;
  const TissueVolumes* deformed = volumes.deformed && !options.reference_only ? &*volumes.deformed : nullptr;
  if (given) check_given(*given, mri, volumes);
  const auto parameters = resolve_tissue_parameters(mri, organs);
  const ImageGrid& grid = volumes.grid;
  const AcquisitionSettings& settings = mri.acquisition;
  const ReceiveCoils coils(grid, settings.coils, object_mask(volumes.reference));
  const std::optional<KspaceSampling> sampling = kspace_sampling(settings, grid);
  // Plans and buffers made once for every coil, sequence and state.
  std::unique_ptr<KspacePipeline> pipeline;
  // Two coils at a time: one sweep over the sum of squares for both, for the memory of one
  // double-precision coil image.
  if (sampling && !options.per_coil && (!given || deformed))
    pipeline = std::make_unique<KspacePipeline>(*sampling, std::min(coils.count(), 2));
  const Acquisition acquisition{grid,           coils,           sampling, settings.bias_percent,
                                pipeline.get(), options.per_coil};
  Workspace workspace;
  images.kspace = acquisition.kspace;
  images.coils = coils.count();
  report_acquisition(acquisition, settings, report);
  ProgressBar progress(reporter, "mri", mri.sequences.size() * ((given ? 0 : 1) + (deformed ? 1 : 0)));
  for (std::size_t q = 0; q < mri.sequences.size(); ++q) {
    throw_if_cancelled();
    const SequenceSettings& sequence = mri.sequences[q];
    std::vector<double> tissue_signal = tissue_signals(sequence, q, volumes.tissues, parameters, report);
    // Signals and noise alike are in scanner units from here on.
    const ReceiverLevels levels = receiver_levels(sequence, settings, parameters, tissue_signal, report);
    const double gain = levels.gain;
    for (double& signal : tissue_signal)
      signal *= gain;
    // Texture: the textured tissues' signals at each voxel's factors (the same gain).
    std::vector<Relaxation> relaxation;
    for (const std::string& tissue : volumes.tissues)
      relaxation.push_back(relaxation_of(parameters, tissue));
    std::optional<TexturedSignal> reference_texture, deformed_texture;
    if (volumes.reference_texture)
      reference_texture.emplace(sequence, volumes.tissues, relaxation, gain, *volumes.reference_texture);
    if (volumes.deformed_texture)
      deformed_texture.emplace(sequence, volumes.tissues, relaxation, gain, *volumes.deformed_texture);
    // One seed per image (sequence and state): images differ, and every run repeats them.
    if (given) {
      images.reference.push_back(std::move(given->images[q]));
      images.reference.back().sequence = &sequence;
      images.reference.back().receiver_gain = gain;
    } else {
      progress.set_detail(sequence.name + ", reference");
      images.reference.push_back(image_of(acquisition, workspace, sequence, mix_seed(mri.seed, 2 * q),
                                          volumes.reference, tissue_signal, levels.sigma,
                                          reference_texture ? &*reference_texture : nullptr));
      images.reference.back().receiver_gain = gain;
      progress.advance();
    }
    if (deformed) {
      progress.set_detail(sequence.name + ", deformed");
      images.deformed.push_back(image_of(acquisition, workspace, sequence, mix_seed(mri.seed, 2 * q + 1),
                                         *deformed, tissue_signal, levels.sigma,
                                         deformed_texture ? &*deformed_texture : nullptr));
      images.deformed.back().receiver_gain = gain;
      progress.advance();
    }
  }
  // The k-space buffers and the voxel workspace are no longer needed: free them before the
  // parameter maps, so that the stage's peak memory is not their sum.
  pipeline.reset();
  workspace = Workspace{};
  if (mri.parameter_maps) add_parameter_maps(volumes, deformed, parameters, given, images, report);
  report.status = "done";
  return images;
}

} // namespace phantasm
