// Balanced SSFP on resonance with alternating RF phase; TE = TR / 2 unless the scene gives it.
#include "mri/sequences/sequence_math.hpp"

namespace phantasm {
namespace bssfp_member {

using namespace sequence_math;

double signal(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
  const double E1 = decay(s.TR_ms, r.T1_ms);
  const double E2 = decay(s.TR_ms, r.T2_ms);
  const double denominator = 1.0 - (E1 - E2) * std::cos(a) - E1 * E2;
  return denominator > 0.0 ? r.PD * std::sin(a) * (1.0 - E1) * decay(s.TE_ms, r.T2_ms) / denominator : 0.0;
}

double bloch(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
  return r.PD * steady_state([&](Magnetization& m) {
           // Two TRs per cycle (RF phase alternates 0, pi); the signal of the second at TE.
           double result = 0.0;
           for (int k = 0; k < 2; ++k) {
             rotate(m, a, k == 0 ? 0.0 : M_PI);
             relax(m, s.TE_ms, r, r.T2_ms);
             result = transverse(m);
             relax(m, s.TR_ms - s.TE_ms, r, r.T2_ms);
           }
           return result;
         });
}

std::vector<SequenceProblem> check(const SequenceSettings& s) {
  // A negative TE was not given: resolve() makes it TR / 2.
  if (s.TE_ms >= 0.0 && std::abs(s.TE_ms - 0.5 * s.TR_ms) > 1e-9 * s.TR_ms) {
    return {{"TE_ms", "expected TE_ms = TR_ms / 2 = " + format_number(0.5 * s.TR_ms) +
                          " (on-resonance bSSFP), found " + format_number(s.TE_ms)}};
  }
  return {};
}

} // namespace bssfp_member

const SequenceType& bssfp_sequence() {
  using namespace bssfp_member;
  static const SequenceType type = [] {
    SequenceParameter TE = echo_time();
    TE.required = false;
    TE.absent = -1.0; // TR / 2 unless given
    SequenceType t{SequenceKind::bssfp,
                   "bssfp",
                   "balanced steady-state free precession (TE = TR / 2)",
                   {TE, flip_angle()}};
    t.gradient_echo = true;
    t.resolve = [](SequenceSettings& s) {
      if (s.TE_ms < 0.0) s.TE_ms = 0.5 * s.TR_ms;
    };
    t.check = bssfp_member::check;
    t.tissue_values = [](const SequenceSettings&) -> std::vector<std::string> {
      return {"T1_ms", "T2_ms", "PD"};
    };
    t.signal = bssfp_member::signal;
    t.bloch = bssfp_member::bloch;
    t.provenance = flip_provenance;
    t.sidecar = flip_sidecar;
    t.plan = flip_text;
    return t;
  }();
  return type;
}

} // namespace phantasm
