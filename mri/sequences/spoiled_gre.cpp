// Spoiled gradient echo (FLASH): the Ernst steady state with T2* decay to the echo.
#include "mri/sequences/sequence_math.hpp"

namespace phantasm {
namespace spoiled_gre_member {

using namespace sequence_math;

double signal(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
  const double E1 = decay(s.TR_ms, r.T1_ms);
  return r.PD * std::sin(a) * (1.0 - E1) / (1.0 - std::cos(a) * E1) * decay(s.TE_ms, r.T2star_ms);
}

double bloch(const SequenceSettings& s, const Relaxation& r) {
  const double a = s.flip_deg * k_degree;
  return r.PD * steady_state([&](Magnetization& m) {
           m.x() = m.y() = 0.0;
           rotate(m, a, 0.0);
           relax(m, s.TE_ms, r, r.T2star_ms);
           const double result = transverse(m);
           relax(m, s.TR_ms - s.TE_ms, r, r.T2star_ms);
           return result;
         });
}

} // namespace spoiled_gre_member

const SequenceType& spoiled_gre_sequence() {
  using namespace spoiled_gre_member;
  static const SequenceType type = [] {
    SequenceType t{SequenceKind::spoiled_gre,
                   "spoiled_gre",
                   "spoiled gradient echo, e.g. T1w, T2starw",
                   {echo_time(), flip_angle()}};
    t.gradient_echo = true;
    t.check = echo_within_repetition;
    t.tissue_values = [](const SequenceSettings&) -> std::vector<std::string> {
      return {"T1_ms", "T2star_ms", "PD"};
    };
    t.signal = spoiled_gre_member::signal;
    t.bloch = spoiled_gre_member::bloch;
    t.provenance = flip_provenance;
    t.sidecar = flip_sidecar;
    t.plan = flip_text;
    return t;
  }();
  return type;
}

} // namespace phantasm
