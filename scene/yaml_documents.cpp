#include "scene/yaml_documents.hpp"

#include "core/format.hpp"

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

/// The first byte of a text that YAML does not allow, as a parser error at its place: a control
/// character (all but tab, line feed and carriage return) or a byte that is not UTF-8. yaml-cpp
/// reads a NUL as "unknown escape character", and keeps other bytes as they are, so that a file
/// name of the scene that is not UTF-8 failed only when provenance.json was written. A text in
/// UTF-16 or UTF-32 (a NUL among its first two bytes, or a byte order mark) is left to yaml-cpp,
/// which reads those.
void reject_bytes_yaml_does_not_hold(const std::string& text) {
  const auto byte_at = [&](std::size_t b) { return static_cast<unsigned char>(text[b]); };
  if (text.size() >= 2 && (text[0] == '\0' || text[1] == '\0' || byte_at(0) == 0xfe || byte_at(0) == 0xff))
    return;
  YAML::Mark at;
  at.pos = at.line = at.column = 0;
  const auto fail = [&](unsigned char byte, const char* what) {
    throw YAML::ParserException(at, format_byte(byte) + ", " + what);
  };
  for (std::size_t b = 0; b < text.size();) {
    const unsigned char byte = byte_at(b);
    std::size_t length = 1;
    if ((byte < 0x20 && byte != '\t' && byte != '\n' && byte != '\r') || byte == 0x7f) {
      fail(byte, "a control character, which YAML text cannot hold");
    } else if (byte >= 0x80) {
      // The second byte's range excludes overlong forms, surrogates and code points past U+10FFFF.
      unsigned char low = 0x80, high = 0xbf;
      if (byte >= 0xc2 && byte <= 0xdf) {
        length = 2;
      } else if (byte >= 0xe0 && byte <= 0xef) {
        length = 3;
        if (byte == 0xe0) low = 0xa0;
        if (byte == 0xed) high = 0x9f;
      } else if (byte >= 0xf0 && byte <= 0xf4) {
        length = 4;
        if (byte == 0xf0) low = 0x90;
        if (byte == 0xf4) high = 0x8f;
      } else {
        fail(byte, "which is not UTF-8 text");
      }
      for (std::size_t k = 1; k < length; ++k) {
        const unsigned char next = b + k < text.size() ? byte_at(b + k) : 0;
        if (next < (k == 1 ? low : 0x80) || next > (k == 1 ? high : 0xbf))
          fail(byte, "which is not UTF-8 text");
      }
    }
    at.pos += static_cast<int>(length);
    if (byte == '\n') {
      ++at.line;
      at.column = 0;
    } else {
      ++at.column;
    }
    b += length;
  }
}

/// Every document of the text, parsed (a document that starts where the one before it did is an
/// error); load_yaml_documents checks the bytes before and the nesting's depth around it.
std::vector<YAML::Node> parse_documents(const std::string& text) {
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
  reject_bytes_yaml_does_not_hold(text);
  try {
    return parse_documents(text);
  } catch (const YAML::DeepRecursion& error) {
    throw YAML::ParserException(error.mark, "lists or mappings nested " + std::to_string(error.depth()) +
                                                " levels deep or more (scenes and sweeps nest a few)");
  }
}

} // namespace phantasm
