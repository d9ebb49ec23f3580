// Text for the HTML report: escaping of every text that comes from a scene or a result file,
// base64 for the embedded pictures, and numbers as people read them.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace phantasm {

/// `text` with &, <, >, " and ' replaced by their HTML entities, so that a scene's name, a path
/// or a log line shows as text wherever it lands (element content or attribute value).
std::string html_escape(std::string_view text);

/// The text html_escape() was given: its five entities turned back into characters (any other
/// entity is left as it is).
std::string html_unescape(std::string_view html);

/// RFC 4648 base64 of `bytes` (with padding), as data: URLs want it.
std::string base64_encode(std::string_view bytes);

/// The bytes of RFC 4648 base64 text (with padding, as base64_encode writes it); nullopt for
/// text that is not (a length not a multiple of 4, a character outside the alphabet, padding
/// before the end).
std::optional<std::string> base64_decode(std::string_view text);

/// A data: URL of PNG bytes, for an <img> embedded in the page.
std::string png_data_url(std::string_view png_bytes);

/// A number with `digits` significant digits ("%.*g"): 0.000123, 12.3, 1.23e+06.
std::string significant(double value, int digits = 3);

/// A self-contained page of tables and plots (no script): its title (HTML, escaped already) as
/// <title> and <h1>, then `body`.
std::string table_page_html(const std::string& title_html, const std::string& body);

} // namespace phantasm
