// MPRAGE: an inversion, then turbo_factor spoiled gradient echoes spaced echo_spacing_ms and
// centred at TI, repeated every TR; the signal is the centre echo's.
#include "mri/sequences/sequence_math.hpp"

#include <algorithm>

namespace phantasm {
namespace mprage_member {

using namespace sequence_math;

/// Recovery before the echo train, then the train, then the rest of the cycle.
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

double signal(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
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
  const double Mz = std::abs(1.0 - A) > 0.0 ? B / (1.0 - A) : B;
  return r.PD * Mz * std::sin(a) * decay(s.TE_ms, r.T2star_ms);
}

double bloch(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
  const MprageTiming t = mprage_timing(s);
  return r.PD * steady_state([&](Magnetization& m) {
           m.x() = m.y() = 0.0;
           rotate(m, M_PI, 0.0);
           relax(m, t.before_train_ms, r, r.T2star_ms);
           double result = 0.0;
           for (int k = 0; k < t.echoes; ++k) {
             m.x() = m.y() = 0.0; // spoiled gradient echoes
             const double longitudinal = m.z();
             rotate(m, a, 0.0);
             if (k == t.centre) {
               Magnetization echo = m;
               relax(echo, s.TE_ms, r, r.T2star_ms);
               result = (longitudinal < 0.0 ? -1.0 : 1.0) * transverse(echo);
             }
             relax(m, t.spacing_ms, r, r.T2star_ms);
           }
           relax(m, t.after_train_ms, r, r.T2star_ms);
           return result;
         });
}

std::vector<SequenceProblem> check(const SequenceSettings& s) {
  // TI runs from the inversion to the centre of the gradient-echo train; the train must fit
  // between the inversion and the next one.
  std::vector<SequenceProblem> problems;
  const double half_train = 0.5 * s.turbo_factor * s.echo_spacing_ms;
  if (s.TE_ms >= s.echo_spacing_ms) {
    problems.push_back({"TE_ms", "expected TE_ms shorter than echo_spacing_ms (" +
                                     format_number(s.echo_spacing_ms) + "), found " +
                                     format_number(s.TE_ms)});
  }
  if (s.TI_ms <= half_train) {
    problems.push_back({"TI_ms", "expected TI_ms greater than half the echo train (" +
                                     format_number(half_train) + " ms), found " + format_number(s.TI_ms)});
  } else if (s.TI_ms + half_train >= s.TR_ms) {
    problems.push_back({"TR_ms", "expected TR_ms greater than TI_ms + half the echo train (" +
                                     format_number(s.TI_ms + half_train) + " ms), found " +
                                     format_number(s.TR_ms)});
  }
  return problems;
}

SequenceFields sidecar(const SequenceSettings& s) {
  // The timing the signal model assumes (docs/volumes-and-images.md, MPRAGE timing).
  return {{"FlipAngle", s.flip_deg},
          {"InversionTime", s.TI_ms / 1000.0},
          {"InversionRecoveryReadout", std::string("gradient_echo")},
          {"EchoSpacing", s.echo_spacing_ms / 1000.0},
          {"TurboFactor", s.turbo_factor},
          {"RepetitionTimePreparation", s.TR_ms / 1000.0},
          {"RepetitionTimeExcitation", s.echo_spacing_ms / 1000.0},
          {"InversionTimeMeasuredTo",
           std::string("excitation of the centre echo of the train (echo TurboFactor/2, counted from 0)")}};
}

} // namespace mprage_member

const SequenceType& mprage_sequence() {
  using namespace mprage_member;
  static const SequenceType type = [] {
    SequenceParameter turbo_factor;
    turbo_factor.key = "turbo_factor";
    turbo_factor.kind = SequenceParameter::Kind::integer;
    turbo_factor.integer = &SequenceSettings::turbo_factor;
    turbo_factor.min = 1;
    turbo_factor.max = 1024;
    SequenceType t{SequenceKind::mprage,
                   "mprage",
                   "magnetization-prepared rapid gradient echo, e.g. T1w, UNIT1",
                   {echo_time(), time("TI_ms", &SequenceSettings::TI_ms), flip_angle(),
                    time("echo_spacing_ms", &SequenceSettings::echo_spacing_ms), turbo_factor}};
    t.gradient_echo = true;
    t.check = mprage_member::check;
    t.tissue_values = [](const SequenceSettings&) -> std::vector<std::string> {
      return {"T1_ms", "T2star_ms", "PD"};
    };
    t.signal = mprage_member::signal;
    t.bloch = mprage_member::bloch;
    t.provenance = [](const SequenceSettings& s) {
      return SequenceFields{{"flip_deg", s.flip_deg},
                            {"TI_ms", s.TI_ms},
                            {"echo_spacing_ms", s.echo_spacing_ms},
                            {"turbo_factor", s.turbo_factor}};
    };
    t.sidecar = mprage_member::sidecar;
    t.plan = [](const SequenceSettings& s) {
      return flip_text(s) + ", TI " + format_number(s.TI_ms) + " ms";
    };
    return t;
  }();
  return type;
}

} // namespace phantasm
