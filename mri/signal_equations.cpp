#include "mri/signal_equations.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

namespace phantasm {
namespace {

constexpr double k_degree = M_PI / 180.0;

/// exp(-t / T), with T -> 0 giving 0 for t > 0 and 1 for t = 0.
double decay(double t_ms, double T_ms) {
  if (t_ms <= 0.0) return 1.0;
  if (T_ms <= 0.0) return 0.0;
  return std::exp(-t_ms / T_ms);
}

/// MPRAGE timing: recovery before the echo train, then the train, then the rest of the cycle.
struct MprageTiming {
  double before_train_ms, spacing_ms, after_train_ms;
  int echoes, centre;
};

MprageTiming mprage_timing(const SequenceSettings& s) {
  MprageTiming t;
  t.echoes = std::max(1, s.turbo_factor);
  t.centre = t.echoes / 2;
  t.spacing_ms = s.echo_spacing_ms;
  // The centre echo's pulse is at TI; pulse k at TI + (k - centre) spacing.
  t.before_train_ms = std::max(0.0, s.TI_ms - t.centre * t.spacing_ms);
  const double train_end = t.before_train_ms + t.echoes * t.spacing_ms;
  t.after_train_ms = std::max(0.0, s.TR_ms - train_end);
  return t;
}

} // namespace

double sequence_signal(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms; // bSSFP: TR / 2 unless given, set by the scene
  const double a = s.flip_deg * k_degree;
  const double E1 = decay(s.TR_ms, r.T1_ms);
  switch (s.kind) {
  case SequenceKind::spin_echo:
    return r.PD * (1.0 - 2.0 * decay(s.TR_ms - 0.5 * TE, r.T1_ms) + E1) * decay(TE, r.T2_ms);
  case SequenceKind::spoiled_gre:
    return r.PD * std::sin(a) * (1.0 - E1) / (1.0 - std::cos(a) * E1) * decay(TE, r.T2star_ms);
  case SequenceKind::inversion_recovery:
    if (s.readout == Readout::spin_echo) {
      // The refocusing pulse at TE/2 also inverts what Mz regrew since the readout.
      return r.PD * (1.0 - 2.0 * decay(s.TI_ms, r.T1_ms) + 2.0 * decay(s.TR_ms - 0.5 * TE, r.T1_ms) - E1) *
             decay(TE, r.T2_ms);
    }
    return r.PD * (1.0 - 2.0 * decay(s.TI_ms, r.T1_ms) + E1) * decay(TE, r.T2star_ms);
  case SequenceKind::bssfp: {
    const double E2 = decay(s.TR_ms, r.T2_ms);
    const double denominator = 1.0 - (E1 - E2) * std::cos(a) - E1 * E2;
    return denominator > 0.0 ? r.PD * std::sin(a) * (1.0 - E1) * decay(TE, r.T2_ms) / denominator : 0.0;
  }
  case SequenceKind::mprage: {
    // Longitudinal magnetization Mz (units of PD) through one cycle is affine: Mz -> A Mz + B.
    const MprageTiming t = mprage_timing(s);
    double A = 1.0, B = 0.0;
    auto recover = [&](double dt) {
      const double e = decay(dt, r.T1_ms);
      A *= e;
      B = B * e + (1.0 - e);
    };
    auto pulse = [&](double cosine) {
      A *= cosine;
      B *= cosine;
    };
    // The cycle starts just before the centre echo's pulse, so its steady state is the signal's.
    double centre_A = 0.0, centre_B = 0.0;
    for (int k = t.centre; k < t.echoes; ++k) {
      pulse(std::cos(a));
      recover(t.spacing_ms);
    }
    recover(t.after_train_ms);
    pulse(-1.0); // inversion
    recover(t.before_train_ms);
    for (int k = 0; k < t.centre; ++k) {
      pulse(std::cos(a));
      recover(t.spacing_ms);
    }
    centre_A = A;
    centre_B = B;
    const double Mz = std::abs(1.0 - centre_A) > 0.0 ? centre_B / (1.0 - centre_A) : centre_B;
    return r.PD * Mz * std::sin(a) * decay(TE, r.T2star_ms);
  }
  }
  return 0.0;
}

namespace {

/// Magnetization (Mx, My, Mz) in units of PD, on resonance.
using Magnetization = Eigen::Vector3d;

void relax(Magnetization& m, double dt_ms, const Relaxation& r, double T2_ms) {
  const double e1 = decay(dt_ms, r.T1_ms), e2 = decay(dt_ms, T2_ms);
  m.x() *= e2;
  m.y() *= e2;
  m.z() = m.z() * e1 + (1.0 - e1);
}

/// A hard pulse of angle a about an axis in the transverse plane at phase phi.
void rotate(Magnetization& m, double a, double phi) {
  m = Eigen::AngleAxisd(a, Eigen::Vector3d(std::cos(phi), std::sin(phi), 0.0)) * m;
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

} // namespace

double bloch_signal(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms; // bSSFP: TR / 2 unless given, set by the scene
  const double a = s.flip_deg * k_degree;
  auto transverse = [](const Magnetization& m) { return std::hypot(m.x(), m.y()); };
  switch (s.kind) {
  case SequenceKind::spin_echo:
    return r.PD * steady_state([&](Magnetization& m) {
             m.x() = m.y() = 0.0; // spoiled before excitation
             rotate(m, M_PI / 2, 0.0);
             relax(m, 0.5 * TE, r, r.T2_ms);
             rotate(m, M_PI, M_PI / 2); // refocusing about y
             relax(m, 0.5 * TE, r, r.T2_ms);
             const double signal = transverse(m);
             relax(m, s.TR_ms - TE, r, r.T2_ms);
             return signal;
           });
  case SequenceKind::spoiled_gre:
    return r.PD * steady_state([&](Magnetization& m) {
             m.x() = m.y() = 0.0;
             rotate(m, a, 0.0);
             relax(m, TE, r, r.T2star_ms);
             const double signal = transverse(m);
             relax(m, s.TR_ms - TE, r, r.T2star_ms);
             return signal;
           });
  case SequenceKind::inversion_recovery:
    return r.PD * steady_state([&](Magnetization& m) {
             m.x() = m.y() = 0.0;
             rotate(m, M_PI, 0.0);
             relax(m, s.TI_ms, r, r.T2_ms);
             m.x() = m.y() = 0.0;
             rotate(m, M_PI / 2, 0.0);
             const double sign = m.y() < 0.0 ? -1.0 : 1.0; // excitation of +z about x gives -y
             if (s.readout == Readout::spin_echo) {
               relax(m, 0.5 * TE, r, r.T2_ms);
               rotate(m, M_PI, M_PI / 2);
               relax(m, 0.5 * TE, r, r.T2_ms);
             } else {
               relax(m, TE, r, r.T2star_ms);
             }
             const double signal = -sign * transverse(m); // signed like the longitudinal magnetization
             relax(m, s.TR_ms - s.TI_ms - TE, r, r.T2_ms);
             return signal;
           });
  case SequenceKind::bssfp: {
    int n = 0;
    return r.PD * steady_state([&](Magnetization& m) {
             // Two TRs per cycle (RF phase alternates 0, pi); the signal of the second at TE.
             double signal = 0.0;
             for (int k = 0; k < 2; ++k, ++n) {
               rotate(m, a, k == 0 ? 0.0 : M_PI);
               relax(m, TE, r, r.T2_ms);
               signal = transverse(m);
               relax(m, s.TR_ms - TE, r, r.T2_ms);
             }
             return signal;
           });
  }
  case SequenceKind::mprage: {
    const MprageTiming t = mprage_timing(s);
    return r.PD * steady_state([&](Magnetization& m) {
             m.x() = m.y() = 0.0;
             rotate(m, M_PI, 0.0);
             relax(m, t.before_train_ms, r, r.T2star_ms);
             double signal = 0.0;
             for (int k = 0; k < t.echoes; ++k) {
               m.x() = m.y() = 0.0; // spoiled gradient echoes
               const double longitudinal = m.z();
               rotate(m, a, 0.0);
               if (k == t.centre) {
                 Magnetization echo = m;
                 relax(echo, TE, r, r.T2star_ms);
                 signal = (longitudinal < 0.0 ? -1.0 : 1.0) * transverse(echo);
               }
               relax(m, t.spacing_ms, r, r.T2star_ms);
             }
             relax(m, t.after_train_ms, r, r.T2star_ms);
             return signal;
           });
  }
  }
  return 0.0;
}

} // namespace phantasm
