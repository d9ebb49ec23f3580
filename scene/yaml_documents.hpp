// Reading every YAML document of a text, safe from a yaml-cpp 0.7 loop.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace phantasm {

/// Every YAML document of a text, as YAML::LoadAll reads them. yaml-cpp 0.7 (Debian 12) answers
/// a stray flow indicator where a document should start (", 0]" at the start of a line) with an
/// empty document that leaves the indicator in place, and LoadAll then adds empty documents
/// until memory runs out (jbeder/yaml-cpp#1040, fixed upstream in 0.8.1). The documents are
/// first walked without building them, and a document that starts where the previous one did is
/// refused. More inputs get a message of their own instead of yaml-cpp's: a control character
/// (yaml-cpp reads a NUL byte as "unknown escape character"), a byte that is not UTF-8 (which
/// yaml-cpp keeps, and JSON output then refuses) and lists or mappings nested deeper than
/// yaml-cpp's limit (which it reports as "bad file").
/// @throws YAML::ParserException at the stray token, the byte or the nesting, or as
/// YAML::LoadAll for other syntax errors
std::vector<YAML::Node> load_yaml_documents(const std::string& text);

} // namespace phantasm
