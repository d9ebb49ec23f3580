// What the sequence members (mri/sequences/*.cpp) share: relaxation, hard pulses, the Bloch
// steady state of a repeated cycle, and the checks and fields most sequences have. Internal to
// the sequences.
#pragma once

#include "core/format.hpp"
#include "mri/sequence_type.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace phantasm::sequence_math {

constexpr double k_degree = M_PI / 180.0;

/// exp(-t / T), with T -> 0 giving 0 for t > 0 and 1 for t = 0.
inline double decay(double t_ms, double T_ms) {
  if (t_ms <= 0.0) return 1.0;
  if (T_ms <= 0.0) return 0.0;
  return std::exp(-t_ms / T_ms);
}

/// Magnetization (Mx, My, Mz) in units of PD, on resonance.
using Magnetization = Eigen::Vector3d;

inline void relax(Magnetization& m, double dt_ms, const Relaxation& r, double T2_ms) {
  const double e1 = decay(dt_ms, r.T1_ms), e2 = decay(dt_ms, T2_ms);
  m.x() *= e2;
  m.y() *= e2;
  m.z() = m.z() * e1 + (1.0 - e1);
}

/// A hard pulse of angle a about an axis in the transverse plane at phase phi.
inline void rotate(Magnetization& m, double a, double phi) {
  m = Eigen::AngleAxisd(a, Eigen::Vector3d(std::cos(phi), std::sin(phi), 0.0)) * m;
}

inline double transverse(const Magnetization& m) {
  return std::hypot(m.x(), m.y());
}

/// Repeats one cycle until the magnetization at its start stops changing; returns the signal
/// the cycle measured in its last run.
template <typename Cycle>
double steady_state(Cycle&& cycle) {
  Magnetization m(0.0, 0.0, 1.0);
  double signal = 0.0;
  for (int n = 0; n < 200000; ++n) {
    const Magnetization before = m;
    signal = cycle(m);
    if ((m - before).cwiseAbs().maxCoeff() < 1e-14 && n > 2) break;
  }
  return signal;
}

/// A time above 0 up to 1e5 ms, required (TI_ms, echo_spacing_ms).
inline SequenceParameter time(const char* key, double SequenceSettings::*member) {
  SequenceParameter p;
  p.key = key;
  p.number = member;
  p.min = 0.0;
  p.max = 1e5;
  p.min_exclusive = true;
  p.unit = "ms";
  return p;
}

/// TE_ms: an echo time of 0 up to 1e5 ms, required.
inline SequenceParameter echo_time() {
  SequenceParameter p = time("TE_ms", &SequenceSettings::TE_ms);
  p.min_exclusive = false;
  return p;
}

/// flip_deg: 0 to 180 degrees, required.
inline SequenceParameter flip_angle() {
  SequenceParameter p;
  p.key = "flip_deg";
  p.number = &SequenceSettings::flip_deg;
  p.min = 0.0;
  p.max = 180.0;
  p.unit = "degrees";
  return p;
}

/// TE below TR, the check of a sequence with one echo per repetition.
inline std::vector<SequenceProblem> echo_within_repetition(const SequenceSettings& s) {
  if (s.TE_ms < s.TR_ms) return {};
  return {{"TE_ms", "expected TE_ms less than TR_ms (" + format_number(s.TR_ms) + "), found " +
                        format_number(s.TE_ms)}};
}

/// The flip angle in provenance.json.
inline SequenceFields flip_provenance(const SequenceSettings& s) {
  return {{"flip_deg", s.flip_deg}};
}

/// The flip angle in the BIDS sidecar.
inline SequenceFields flip_sidecar(const SequenceSettings& s) {
  return {{"FlipAngle", s.flip_deg}};
}

/// ", flip 25 deg".
inline std::string flip_text(const SequenceSettings& s) {
  return ", flip " + format_number(s.flip_deg) + " deg";
}

} // namespace phantasm::sequence_math
