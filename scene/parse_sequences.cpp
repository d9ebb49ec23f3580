#include "scene/parse_sections.hpp"

namespace phantasm::scene_detail {
namespace {

const NumberRule k_time_rule{0.0, 1e5, true, false, "ms"};
const NumberRule k_echo_time_rule{0.0, 1e5, false, false, "ms"};

void parse_sequence(CheckedMap& map, SequenceSettings& sequence) {
  if (map.string("name", sequence.name, true) && !is_bids_label(sequence.name)) {
    map.context().problem(map.get("name"), map.child_path("name"),
                          "expected a BIDS suffix (letters and digits, e.g. T1w), found '" + sequence.name +
                              "'");
  }
  std::string kind;
  if (!map.choice("type", kind, {"spin_echo", "spoiled_gre", "inversion_recovery", "bssfp", "mprage"},
                  true)) {
    map.accept_remaining_keys();
    return;
  }
  map.number("TR_ms", sequence.TR_ms, k_time_rule, true);
  const NumberRule flip_rule = between(0.0, 180.0, "degrees");
  if (kind == "spin_echo") {
    sequence.kind = SequenceKind::spin_echo;
    map.number("TE_ms", sequence.TE_ms, k_echo_time_rule, true);
  } else if (kind == "spoiled_gre") {
    sequence.kind = SequenceKind::spoiled_gre;
    map.number("TE_ms", sequence.TE_ms, k_echo_time_rule, true);
    map.number("flip_deg", sequence.flip_deg, flip_rule, true);
  } else if (kind == "inversion_recovery") {
    sequence.kind = SequenceKind::inversion_recovery;
    map.number("TE_ms", sequence.TE_ms, k_echo_time_rule, true);
    map.number("TI_ms", sequence.TI_ms, k_time_rule, true);
    std::string readout;
    if (map.choice("readout", readout, {"gradient_echo", "spin_echo"}, true)) {
      sequence.readout = readout == "spin_echo" ? Readout::spin_echo : Readout::gradient_echo;
    }
  } else if (kind == "bssfp") {
    sequence.kind = SequenceKind::bssfp;
    sequence.TE_ms = -1.0; // TR/2 unless given
    map.number("TE_ms", sequence.TE_ms, k_echo_time_rule);
    map.number("flip_deg", sequence.flip_deg, flip_rule, true);
  } else {
    sequence.kind = SequenceKind::mprage;
    map.number("TE_ms", sequence.TE_ms, k_echo_time_rule, true);
    map.number("TI_ms", sequence.TI_ms, k_time_rule, true);
    map.number("flip_deg", sequence.flip_deg, flip_rule, true);
    map.number("echo_spacing_ms", sequence.echo_spacing_ms, k_time_rule, true);
    map.integer("turbo_factor", sequence.turbo_factor, 1, 1024, true);
  }
}

} // namespace

void parse_sequences(YamlContext& context, const YAML::Node& node, std::vector<SequenceSettings>& sequences) {
  if (!node.IsSequence()) {
    context.problem(node, "sequences", "expected a list of sequences, found " + describe(node));
    return;
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    CheckedMap entry(context, node[i], "sequences[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    SequenceSettings sequence;
    parse_sequence(entry, sequence);
    sequences.push_back(sequence);
  }
}

} // namespace phantasm::scene_detail
