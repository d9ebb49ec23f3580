#include "scene/yaml_documents.hpp"

#include <yaml-cpp/depthguard.h>
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

/// The first control character of a UTF-8 text (YAML allows tab, line feed and carriage return
/// only), as a parser error at its place. A text in UTF-16 or UTF-32 (a NUL among its first two
/// bytes, or a byte order mark) is left to yaml-cpp, which reads those.
void reject_control_characters(const std::string& text) {
  if (text.size() >= 2 &&
      (text[0] == '\0' || text[1] == '\0' || static_cast<unsigned char>(text[0]) == 0xfe ||
       static_cast<unsigned char>(text[0]) == 0xff))
    return;
  YAML::Mark at;
  at.pos = at.line = at.column = 0;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && c != '\t' && c != '\n' && c != '\r') || byte == 0x7f) {
      static const char* digits = "0123456789abcdef";
      throw YAML::ParserException(at, std::string("a control character (byte 0x") + digits[byte >> 4] +
                                          digits[byte & 15] + "), which YAML text cannot hold");
    }
    ++at.pos;
    if (c == '\n') {
      ++at.line;
      at.column = 0;
    } else {
      ++at.column;
    }
  }
}

/// load_yaml_documents without its checks of the text and of the nesting.
std::vector<YAML::Node> load_checked_documents(const std::string& text) {
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

} // namespace

std::vector<YAML::Node> load_yaml_documents(const std::string& text) {
  reject_control_characters(text);
  try {
    return load_checked_documents(text);
  } catch (const YAML::DeepRecursion& error) {
    throw YAML::ParserException(error.mark, "lists or mappings nested " + std::to_string(error.depth()) +
                                                " levels deep or more (scenes and sweeps nest a few)");
  }
}

} // namespace phantasm
