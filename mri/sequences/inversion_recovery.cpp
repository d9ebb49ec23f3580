// Inversion recovery: an inversion, TI later a 90-degree excitation read by a gradient echo or
// a spin echo; the signal keeps the sign of the longitudinal magnetization (e.g. FLAIR).
#include "mri/sequences/sequence_math.hpp"

namespace phantasm {
namespace inversion_recovery_member {

using namespace sequence_math;

double signal(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms;
  const double E1 = decay(s.TR_ms, r.T1_ms);
  if (s.readout == Readout::spin_echo) {
    // The refocusing pulse at TE/2 also inverts what Mz regrew since the readout.
    return r.PD * (1.0 - 2.0 * decay(s.TI_ms, r.T1_ms) + 2.0 * decay(s.TR_ms - 0.5 * TE, r.T1_ms) - E1) *
           decay(TE, r.T2_ms);
  }
  return r.PD * (1.0 - 2.0 * decay(s.TI_ms, r.T1_ms) + E1) * decay(TE, r.T2star_ms);
}

double bloch(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms;
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
           const double result = -sign * transverse(m); // signed like the longitudinal magnetization
           relax(m, s.TR_ms - s.TI_ms - TE, r, r.T2_ms);
           return result;
         });
}

std::vector<SequenceProblem> check(const SequenceSettings& s) {
  std::vector<SequenceProblem> problems = echo_within_repetition(s);
  if (s.TI_ms + s.TE_ms >= s.TR_ms) {
    problems.push_back({"TI_ms", "expected TI_ms + TE_ms less than TR_ms (" + format_number(s.TR_ms) +
                                     "), found " + format_number(s.TI_ms + s.TE_ms)});
  }
  return problems;
}

} // namespace inversion_recovery_member

const SequenceType& inversion_recovery_sequence() {
  using namespace inversion_recovery_member;
  static const SequenceType type = [] {
    SequenceParameter readout;
    readout.key = "readout";
    readout.kind = SequenceParameter::Kind::readout;
    SequenceType t{SequenceKind::inversion_recovery,
                   "inversion_recovery",
                   "inversion recovery with a gradient-echo or spin-echo readout, e.g. FLAIR",
                   {echo_time(), time("TI_ms", &SequenceSettings::TI_ms), readout}};
    t.check = inversion_recovery_member::check;
    t.tissue_values = [](const SequenceSettings& s) -> std::vector<std::string> {
      return {"T1_ms", s.readout == Readout::spin_echo ? "T2_ms" : "T2star_ms", "PD"};
    };
    t.signal = inversion_recovery_member::signal;
    t.bloch = inversion_recovery_member::bloch;
    t.provenance = [](const SequenceSettings& s) {
      return SequenceFields{{"flip_deg", s.flip_deg}, {"TI_ms", s.TI_ms}, {"readout", to_string(s.readout)}};
    };
    t.sidecar = [](const SequenceSettings& s) {
      return SequenceFields{{"FlipAngle", s.flip_deg},
                            {"InversionTime", s.TI_ms / 1000.0},
                            {"InversionRecoveryReadout", to_string(s.readout)}};
    };
    t.plan = [](const SequenceSettings& s) {
      return flip_text(s) + ", TI " + format_number(s.TI_ms) + " ms";
    };
    return t;
  }();
  return type;
}

} // namespace phantasm
