#include "mri/sequence_type.hpp"
#include "scene/declared_keys.hpp"
#include "scene/parse_sections.hpp"

namespace phantasm::scene_detail {
namespace {

/// Reads a sequence: name, type and TR_ms, then the keys its member of the registry reads.
void parse_sequence(CheckedMap& map, SequenceSettings& sequence) {
  if (read_declared_keys(map, sequence, {"name"}).count("name") && !is_bids_label(sequence.name)) {
    map.context().problem(map.get("name"), map.child_path("name"),
                          "expected a BIDS suffix (letters and digits, e.g. T1w), found '" + sequence.name +
                              "'");
  }
  std::string kind;
  if (!map.choice("type", kind, sequence_type_names(), true)) {
    map.accept_remaining_keys();
    return;
  }
  const SequenceType& type = *find_sequence_type(kind);
  sequence.kind = type.kind;
  read_declared_keys(map, sequence, {"TR_ms"}); // every type's key; the others are the type's
  for (const SequenceParameter& p : type.parameters) {
    switch (p.kind) {
    case SequenceParameter::Kind::number:
      if (!p.required) sequence.*p.number = p.absent;
      map.number(p.key, sequence.*p.number,
                 NumberRule{p.min, p.max, p.min_exclusive, p.max_exclusive, p.unit}, p.required);
      break;
    case SequenceParameter::Kind::integer:
      map.integer(p.key, sequence.*p.integer, static_cast<int>(p.min), static_cast<int>(p.max), p.required);
      break;
    case SequenceParameter::Kind::readout:
      // The readouts and their names are the declaration's (scene/settings_declarations.cpp).
      read_declared_key(map, sequence, p.key, p.required);
      break;
    }
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
