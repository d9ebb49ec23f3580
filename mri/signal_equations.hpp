// The closed-form steady-state signals of the scene's sequences (spin echo, spoiled gradient
// echo, inversion recovery, bSSFP, MPRAGE) for one tissue's relaxation parameters, signed; each
// sequence's own in its member of the registry (mri/sequence_type.hpp, mri/sequences/).
#pragma once

#include "mri/sequence_type.hpp"

namespace phantasm {

/// The closed-form steady-state signal of a sequence for one tissue (docs/volumes-and-images.md, MR images),
/// signed: inversion-recovery and MPRAGE signals keep the sign of the longitudinal
/// magnetization at readout, so partial-volume mixing can cancel; images take the magnitude.
/// * spin echo: PD (1 - 2 exp(-(TR - TE/2)/T1) + E1) exp(-TE/T2) (ideal 90-180, spoiled before
///   each excitation)
/// * spoiled gradient echo: PD sin a (1 - E1) / (1 - cos a E1) exp(-TE/T2*)
/// * inversion recovery, gradient-echo readout: PD (1 - 2 exp(-TI/T1) + E1) exp(-TE/T2*);
///   spin-echo readout (the refocusing pulse inverts the regrown Mz too):
///   PD (1 - 2 exp(-TI/T1) + 2 exp(-(TR - TE/2)/T1) - E1) exp(-TE/T2)
/// * bSSFP on resonance, alternating RF phase, TE = TR/2:
///   PD sin a (1 - E1) exp(-TE/T2) / (1 - (E1 - E2) cos a - E1 E2)
/// * MPRAGE: inversion, then turbo_factor spoiled gradient echoes spaced echo_spacing and
///   centred at TI, repeated every TR; the steady state of that cycle in closed form, signal at
///   the centre echo.
double sequence_signal(const SequenceSettings& sequence, const Relaxation& tissue);

/// The same signal by propagating the magnetization vector through the sequence with hard
/// pulses (rotations) and exact relaxation between them, cycle after cycle until the steady
/// state (change below 1e-13 of PD) or 200000 cycles: an independent check of the closed forms.
double bloch_signal(const SequenceSettings& sequence, const Relaxation& tissue);

} // namespace phantasm
