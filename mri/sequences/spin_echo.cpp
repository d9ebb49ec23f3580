// Spin echo: an ideal 90-180 pair, spoiled before each excitation.
#include "mri/sequences/sequence_math.hpp"

namespace phantasm {
namespace spin_echo_member {

using namespace sequence_math;

double signal(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms;
  const double E1 = decay(s.TR_ms, r.T1_ms);
  return r.PD * (1.0 - 2.0 * decay(s.TR_ms - 0.5 * TE, r.T1_ms) + E1) * decay(TE, r.T2_ms);
}

double bloch(const SequenceSettings& s, const Relaxation& r) {
  const double TE = s.TE_ms;
  return r.PD * steady_state([&](Magnetization& m) {
           m.x() = m.y() = 0.0; // spoiled before excitation
           rotate(m, M_PI / 2, 0.0);
           relax(m, 0.5 * TE, r, r.T2_ms);
           rotate(m, M_PI, M_PI / 2); // refocusing about y
           relax(m, 0.5 * TE, r, r.T2_ms);
           const double result = transverse(m);
           relax(m, s.TR_ms - TE, r, r.T2_ms);
           return result;
         });
}

} // namespace spin_echo_member

const SequenceType& spin_echo_sequence() {
  using namespace spin_echo_member;
  static const SequenceType type = [] {
    SequenceType t{SequenceKind::spin_echo, "spin_echo", "spin echo (90-180), e.g. T2w, PDw", {echo_time()}};
    t.check = echo_within_repetition;
    t.tissue_values = [](const SequenceSettings&) -> std::vector<std::string> {
      return {"T1_ms", "T2_ms", "PD"};
    };
    t.signal = spin_echo_member::signal;
    t.bloch = spin_echo_member::bloch;
    t.provenance = [](const SequenceSettings&) { return SequenceFields{}; };
    t.sidecar = [](const SequenceSettings&) { return SequenceFields{{"FlipAngle", 90.0}}; };
    t.plan = [](const SequenceSettings&) { return std::string(); };
    return t;
  }();
  return type;
}

} // namespace phantasm
