// Simulated acquisition in k-space: the central samples an acquisition keeps, the slice profile,
// complex noise per k-space line and zero-filled reconstruction (FFTW), thread-count independent.
#pragma once

#include "core/grid.hpp"

#include <complex>
#include <cstdint>
#include <mutex>
#include <vector>

namespace phantasm {

/// What an acquisition keeps of an object sampled on the phantom grid: the central
/// acquired.x x acquired.y x acquired.z samples of its discrete Fourier transform, weighted
/// along the third axis by the transform of a rectangular slice profile.
struct KspaceSampling {
  Eigen::Vector3i dims{1, 1, 1};     ///< the object grid's samples per axis
  Eigen::Vector3i acquired{1, 1, 1}; ///< k-space samples kept per axis, 1 <= acquired <= dims
  double slice_thickness_voxels = 0; ///< rectangular slice profile along k, in object voxels; 0: none

  /// True when every sample is kept and there is no slice profile: the acquisition is the identity.
  bool keeps_everything() const { return acquired == dims && slice_thickness_voxels <= 0.0; }
};

/// The signed frequency index of DFT sample `index` of `n` (0, 1, ..., -2, -1).
int signed_frequency(int index, int n);

/// True when the signed frequency of DFT sample `index` of `n` is among the `kept` central ones:
/// [-kept/2, (kept - 1)/2] after rounding down, so an even count keeps one more negative frequency,
/// as scanners do.
bool is_kept_frequency(int index, int n, int kept);

/// FFTW's planner is not thread-safe: every plan is made and destroyed under this lock.
std::mutex& fftw_planner_lock();

/// One receive coil of a k-space acquisition: its in-plane sensitivities and its noise.
struct KspaceCoil {
  const std::complex<double>* sensitivity = nullptr; ///< nx x ny (x fastest); nullptr: uniform 1
  double noise_sigma = 0.0;                          ///< std of each part of a reconstructed voxel's noise
  std::uint64_t noise_seed = 0;
};

/// The k-space acquisition of many images of one grid: sensitivity (in-plane, the same on every
/// slice) x a real object, with the same sampling, plans and buffers for every coil, sequence
/// and state. Equal to reference::acquire_in_kspace() (mri/kspace_reference.hpp, the former
/// method, for tests and benchmarks) of sensitivity x object up to single-precision
/// rounding (tested to 1e-6 of the largest value), noise apart (another generator, the same
/// statistics):
/// * the object is real, so its transform along the third axis is real-to-complex, and the
///   sensitivity does not vary along that axis, so this transform, the truncation along it and
///   the slice profile are done once per object (set_object()), not once per coil;
/// * each coil's kept planes along the third axis are then transformed in-plane one plane at a
///   time (a plane stays in cache), truncated, given noise and transformed back, and only the
///   kept planes are transformed back along the third axis;
/// * the in-plane truncation stays per coil: applying it once to the object and multiplying by
///   the sensitivities afterwards differs from the acquisition by up to 0.4 % of the white-matter
///   signal at 1 mm for 8 coils (docs/volumes-and-images.md, k-space acquisition);
/// * transforms and buffers are single precision (fftw3f), the precision of the images: twice
///   the transform speed and half the memory traffic of double precision; the sum of squares
///   is accumulated in double precision;
/// * FFTW plans are made once (FFTW_ESTIMATE: the same bytes on every run), out of place, and
///   used by all threads on buffers of one alignment; noise is drawn from one NormalStream per
///   coil and kept k-space column, seeded from the coil's noise seed and the column's
///   frequencies. The result does not depend on the number of threads.
class KspacePipeline {
public:
  /// @param coils_together coils whose planes are held at once (memory: each holds the kept
  ///   planes along z in single precision); the through-plane pass adds their squared
  ///   magnitudes in one sweep over the sum of squares
  explicit KspacePipeline(const KspaceSampling& sampling, int coils_together = 1);
  ~KspacePipeline();
  KspacePipeline(const KspacePipeline&) = delete;
  KspacePipeline& operator=(const KspacePipeline&) = delete;

  const KspaceSampling& sampling() const { return m_sampling; }
  int coils_together() const { return m_coils_together; }

  /// Transforms the real object along the third axis and keeps its truncated, slice-weighted
  /// half spectrum for the coils that follow.
  /// @param object dims.prod() values, x fastest
  void set_object(const std::vector<double>& object);
  /// The same for an object already rounded to single precision (the precision of the
  /// transforms): the same spectrum as the double-precision object whose values round to these.
  /// @param object dims.prod() values, x fastest
  void set_object(const float* object);

  /// Acquires one coil image of the object of set_object() and writes it (complex, on the grid).
  /// @param sensitivity dims.x() x dims.y() complex sensitivities (x fastest), or nullptr for 1
  /// @param noise_sigma std of each part of a reconstructed voxel's noise
  /// @param image resized to dims.prod()
  void acquire(const std::complex<double>* sensitivity, double noise_sigma, std::uint64_t noise_seed,
               std::vector<std::complex<double>>& image);

  /// Acquires the coils' images of the object, coils_together() at a time, and adds the squared
  /// magnitude of each voxel of each to `energy` (the sum of squares).
  /// @param energy dims.prod() values
  void add_squared_magnitude(const std::vector<KspaceCoil>& coils, std::vector<double>& energy);

  /// One group of a sum of squares over several groups of coils: acquires `count` <=
  /// coils_together() coils and adds their squared magnitudes to the sum as the call above does
  /// (the same arithmetic in the same order: the same bytes), with fewer passes over the sum.
  /// @param first the first group: the sum starts at 0 and `energy` is not read
  /// @param energy dims.prod() values: the sum before the group (unless `first`) and after it
  ///   (unless `magnitude`); unused, and may be nullptr, when both
  /// @param magnitude nullptr, or dims.prod() values: the last group writes the root of the sum
  ///   there, rounded to float, instead of storing the sum
  void add_squared_magnitude(const KspaceCoil* coils, int count, bool first, double* energy,
                             float* magnitude);

private:
  struct Plans;
  /// Where acquire_coils() delivers the coils' images.
  struct Delivery {
    std::complex<double>* image = nullptr; ///< one coil's image, or
    double* energy = nullptr;              ///< the sum of squares (see add_squared_magnitude())
    bool first = false;                    ///< the sum starts at 0: `energy` is not read
    float* magnitude = nullptr;            ///< the root of the sum, instead of storing it
  };
  /// `count` <= coils_together() coils, delivered as `to` says.
  void acquire_coils(const KspaceCoil* coils, int count, const Delivery& to);
  /// acquire_coils()'s in-plane part: each coil's kept planes along z, multiplied by its
  /// sensitivity, truncated, with noise, transformed back in the plane.
  void transform_in_plane(const KspaceCoil* coils, int count);
  /// acquire_coils()'s part along z: the coils' planes transformed back along z, one in-plane
  /// row at a time, and delivered as `to` says.
  void transform_along_z(int count, const Delivery& to);
  /// set_object() from values of either precision.
  template <class Value>
  void transform_object(const Value* object);

  KspaceSampling m_sampling;
  int m_coils_together = 1;
  int m_row = 0;                             ///< complex stride between in-plane rows (64-byte multiple)
  std::size_t m_plane = 0;                   ///< complex stride between planes
  int m_column = 0;                          ///< complex stride between transposed columns
  std::vector<int> m_kept_x, m_kept_z;       ///< kept DFT indices along x and along z
  std::vector<int> m_kept_y, m_dropped_y;    ///< DFT indices along y kept and dropped
  int m_half = 0;                            ///< non-negative frequencies kept along z: 0 .. m_half - 1
  std::vector<char> m_row_used;              ///< per in-plane row: does the object reach it
  std::complex<float>* m_spectrum = nullptr; ///< m_half planes: the object's half spectrum along z
  std::complex<float>* m_coil = nullptr;     ///< m_kept_z.size() planes of each of coils_together()
  Plans* m_plans = nullptr;
};

/// A seed mixed from a base seed and a stream number (splitmix64): independent streams for
/// images, coils and lines that every run repeats.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream);

} // namespace phantasm
