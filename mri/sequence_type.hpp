// The registry of MR sequence types: one member per sequence (mri/sequences/*.cpp), each the one
// place that knows its scene keys, its defaults and timing checks, the tissue values it reads,
// its signal (closed form and Bloch simulation), its provenance and BIDS sidecar fields and its
// plan line. Adding a sequence: docs/architecture.md, "Adding a variant".
#pragma once

#include "mri/mri_settings.hpp"

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace phantasm {

/// Relaxation parameters of one tissue (times in ms, PD relative).
struct Relaxation {
  double PD = 1.0;
  double T1_ms = 1000.0;
  double T2_ms = 100.0;
  double T2star_ms = 50.0;
};

/// A scene key a sequence reads beyond name, type and TR_ms (which every sequence reads).
struct SequenceParameter {
  enum class Kind { number, integer, readout };
  const char* key = "";
  Kind kind = Kind::number;
  double SequenceSettings::*number = nullptr; ///< Kind::number
  int SequenceSettings::*integer = nullptr;   ///< Kind::integer
  double min = 0.0, max = 0.0;                ///< accepted values (integers: inclusive)
  bool min_exclusive = false, max_exclusive = false;
  const char* unit = "";
  bool required = true;
  double absent = 0.0; ///< the value when not required and not given (a number)
};

/// A value of a sequence's provenance or BIDS sidecar field.
using SequenceValue = std::variant<double, int, std::string>;
/// Named values, in order.
using SequenceFields = std::vector<std::pair<std::string, SequenceValue>>;

/// A problem of a sequence's timing: the key it is about and "expected ..., found ...".
struct SequenceProblem {
  std::string key;
  std::string message;
};

/// One sequence type of the registry.
struct SequenceType {
  SequenceKind kind;
  const char* name;        ///< the scene's `type`
  const char* description; ///< one line for help and the docs' table
  std::vector<SequenceParameter> parameters;
  /// Gradient-echo excitations: a flip angle of 0 or 180 degrees leaves no signal.
  bool gradient_echo = false;
  /// Fills values that depend on others (bSSFP: TE = TR / 2 unless given); may be null.
  void (*resolve)(SequenceSettings&) = nullptr;
  /// The timing problems of a parsed sequence (none: consistent).
  std::vector<SequenceProblem> (*check)(const SequenceSettings&) = nullptr;
  /// The tissue quantities the signal reads ("T1_ms", "T2_ms", "T2star_ms", "PD").
  std::vector<std::string> (*tissue_values)(const SequenceSettings&) = nullptr;
  /// The closed-form steady-state signal, signed (mri/signal_equations.hpp).
  double (*signal)(const SequenceSettings&, const Relaxation&) = nullptr;
  /// The same signal by Bloch simulation of the sequence's cycle: an independent check.
  double (*bloch)(const SequenceSettings&, const Relaxation&) = nullptr;
  /// Its settings in provenance.json beyond name, type, TR_ms and TE_ms.
  SequenceFields (*provenance)(const SequenceSettings&) = nullptr;
  /// Its BIDS sidecar fields beyond the common ones (times in seconds, angles in degrees).
  SequenceFields (*sidecar)(const SequenceSettings&) = nullptr;
  /// Its part of the plan line after "TR ..., TE ..." (", flip 25 deg").
  std::string (*plan)(const SequenceSettings&) = nullptr;
};

/// Every registered sequence type, in the docs' order.
const std::vector<const SequenceType*>& sequence_types();

/// The member of a kind (every kind has one).
const SequenceType& sequence_type(SequenceKind kind);

/// The member named `name`, or null.
const SequenceType* find_sequence_type(const std::string& name);

/// The registered names, in order.
std::vector<std::string> sequence_type_names();

} // namespace phantasm
