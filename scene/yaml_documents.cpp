#include "scene/yaml_documents.hpp"

#include <yaml-cpp/eventhandler.h>

#include <cctype>
#include <sstream>

namespace phantasm {
namespace {

/// Records where each document starts, and nothing else.
class DocumentStarts final : public YAML::EventHandler {
public:
  std::vector<YAML::Mark> starts;

  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
  }
  void OnMapEnd() override {}
};

} // namespace

std::vector<YAML::Node> load_yaml_documents(const std::string& text) {
  std::istringstream stream(text);
  YAML::Parser parser(stream);
  DocumentStarts documents;
  while (parser.HandleNextDocument(documents)) {
    const std::size_t n = documents.starts.size();
    if (n >= 2 && documents.starts[n - 1].pos == documents.starts[n - 2].pos) {
      const YAML::Mark& at = documents.starts[n - 1];
      const unsigned char c = at.pos >= 0 && static_cast<std::size_t>(at.pos) < text.size()
                                  ? text[static_cast<std::size_t>(at.pos)]
                                  : 0;
      const std::string token = std::isgraph(c) ? std::string("'") + static_cast<char>(c) + "'"
                                                : "character " + std::to_string(static_cast<int>(c));
      throw YAML::ParserException(at, "unexpected " + token + " where a value or a key should start");
    }
  }
  return YAML::LoadAll(text);
}

} // namespace phantasm
