// Settings declared once: each field of a settings struct with its name, type, unit, bounds,
// help and the cached results it shapes, and what every reader of settings (the scene's parser,
// the caches' keys, `phantasm info --settings`, the docs' table, the tests) takes from that
// declaration.
// scene/settings_declarations.hpp declares the settings of every stage with it.
#pragma once

#include "core/format.hpp"
#include "core/number_rule.hpp"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace phantasm {

/// A double as a hex float: a key changes with any bit of a setting.
std::string exact_text(double value);

/// A matrix's values as hex floats, column by column: "[a b c]".
template <typename Derived>
std::string exact_text(const Eigen::MatrixBase<Derived>& m) {
  std::string out = "[";
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      out += (r + c > 0 ? " " : "") + exact_text(static_cast<double>(m(r, c)));
  return out + "]";
}

/// A string as a JSON string literal.
std::string json_string(const std::string& text);

/// A double as a JSON number that reads back as the same double and as a number with a fraction
/// ("256.0", not "256": a JSON library keeps it a floating-point number).
std::string json_number(double value);

/// The cached results a run keeps across runs, as bits: a setting names those it shapes. Each is
/// made from one before it (the reference state and the bodies' tet meshes from the anatomy, the
/// reference images from the state), so its key holds that one's key: a setting that shapes the
/// anatomy changes all four.
enum CacheKeys : unsigned {
  no_cached_result = 0,
  cached_anatomy = 1,          ///< organ geometry (pipeline/anatomy_cache.hpp)
  cached_reference_state = 2,  ///< level sets, labels, fractions (pipeline/reference_cache.hpp)
  cached_reference_images = 4, ///< reference MR images and maps (pipeline/reference_images_cache.hpp)
  /// the deformation's tet meshes of bodies with nested organs (pipeline/body_mesh_cache.hpp): its
  /// key names the body and the organs it carries, which the organs' motion decides
  cached_body_meshes = 8,
};

/// The keys that change with a setting that shapes `keys`: those and every one made after them.
unsigned keys_changed_by(unsigned keys);

/// How one type of value is written in a key (exactly, each value delimiting itself), shown to a
/// reader, named, and changed to another value (the tests' change of each setting).
template <typename T, typename Enable = void>
struct SettingValue;

template <>
struct SettingValue<double> {
  static std::string exact(double v) { return exact_text(v); }
  static std::string shown(double v) { return format_number(v); }
  static std::string type() { return "number"; }
  static std::string json(double v) { return json_number(v); }
  static void change(double& v) { v += 1.0 + 0.5 * std::abs(v); } // larger, whatever v is
};

template <typename T>
struct SettingValue<T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>>> {
  static std::string exact(T v) { return std::to_string(v); }
  static std::string shown(T v) { return std::to_string(v); }
  static std::string type() { return "integer"; }
  static std::string json(T v) { return std::to_string(v); }
  static void change(T& v) { v = static_cast<T>(v + 1); }
};

template <>
struct SettingValue<bool> {
  static std::string exact(bool v) { return v ? "true" : "false"; }
  static std::string shown(bool v) { return exact(v); }
  static std::string type() { return "boolean"; }
  static std::string json(bool v) { return exact(v); }
  static void change(bool& v) { v = !v; }
};

template <>
struct SettingValue<std::string> {
  /// The length and the characters: no text can pass for another field.
  static std::string exact(const std::string& v) { return std::to_string(v.size()) + ":" + v; }
  static std::string shown(const std::string& v) { return v.empty() ? "(none)" : v; }
  static std::string type() { return "text"; }
  static std::string json(const std::string& v) { return json_string(v); }
  static void change(std::string& v) { v += "x"; }
};

template <>
struct SettingValue<std::filesystem::path> {
  static std::string exact(const std::filesystem::path& v) {
    return SettingValue<std::string>::exact(v.string());
  }
  static std::string shown(const std::filesystem::path& v) {
    return SettingValue<std::string>::shown(v.string());
  }
  static std::string type() { return "path"; }
  static std::string json(const std::filesystem::path& v) { return json_string(v.string()); }
  static void change(std::filesystem::path& v) { v += "x"; }
};

template <typename Scalar>
struct SettingValue<Eigen::Matrix<Scalar, 3, 1>> {
  using V = Eigen::Matrix<Scalar, 3, 1>;
  static std::string exact(const V& v) { return exact_text(v); }
  static std::string shown(const V& v) { return format_vector(v.template cast<double>()); }
  static std::string type() { return std::is_integral_v<Scalar> ? "3 integers" : "3 numbers"; }
  static std::string json(const V& v) {
    return "[" + SettingValue<Scalar>::json(v.x()) + "," + SettingValue<Scalar>::json(v.y()) + "," +
           SettingValue<Scalar>::json(v.z()) + "]";
  }
  static void change(V& v) { SettingValue<Scalar>::change(v.x()); }
  static V some() { return V::Ones(); }
};

template <typename T>
struct SettingValue<std::optional<T>> {
  static std::string exact(const std::optional<T>& v) { return v ? SettingValue<T>::exact(*v) : "none"; }
  static std::string shown(const std::optional<T>& v) { return v ? SettingValue<T>::shown(*v) : "(unset)"; }
  static std::string type() { return SettingValue<T>::type() + " or unset"; }
  static std::string json(const std::optional<T>& v) { return v ? SettingValue<T>::json(*v) : "null"; }
  static void change(std::optional<T>& v) {
    if (!v) {
      if constexpr (std::is_arithmetic_v<T>)
        v = T{};
      else
        v = SettingValue<T>::some();
    }
    SettingValue<T>::change(*v);
  }
};

template <typename T>
struct SettingValue<std::vector<T>> {
  static std::string exact(const std::vector<T>& v) {
    std::string out = "[" + std::to_string(v.size()) + ":";
    for (const T& e : v)
      out += " " + SettingValue<T>::exact(e);
    return out + "]";
  }
  static std::string shown(const std::vector<T>& v) {
    std::string out;
    for (const T& e : v)
      out += (out.empty() ? "" : ", ") + SettingValue<T>::shown(e);
    return "[" + out + "]";
  }
  static std::string type() { return "list of " + SettingValue<T>::type(); }
  static std::string json(const std::vector<T>& v) {
    std::string out;
    for (const T& e : v)
      out += (out.empty() ? "" : ",") + SettingValue<T>::json(e);
    return "[" + out + "]";
  }
  static void change(std::vector<T>& v) { v.emplace_back(); }
};

/// Reads the value of one key of a section of settings (the scene's checked YAML mapping,
/// scene/declared_keys.hpp): each returns false when the key is absent or after reporting a
/// problem with it (a required key that is absent is one).
class SettingReader {
public:
  virtual ~SettingReader() = default;
  virtual bool number(const std::string& key, double& out, const NumberRule& rule, bool required) = 0;
  virtual bool integer(const std::string& key, int& out, const NumberRule& rule, bool required) = 0;
  virtual bool boolean(const std::string& key, bool& out, bool required) = 0;
  virtual bool text(const std::string& key, std::string& out, bool required) = 0;
  virtual bool texts(const std::string& key, std::vector<std::string>& out, bool required) = 0;
  /// With scalar_allowed one number stands for all three.
  virtual bool vec3(const std::string& key, Eigen::Vector3d& out, const NumberRule& rule, bool required,
                    bool scalar_allowed) = 0;
  virtual bool choice(const std::string& key, std::string& out, const std::vector<std::string>& choices,
                      bool required) = 0;
};

/// How a value of type T is read by a SettingReader, for the types a scene key holds as a plain
/// value; `readable` is false for the others (their keys are read by hand).
template <typename T>
struct SettingRead {
  static constexpr bool readable = false;
};

/// What reading a key takes from its field's declaration.
struct ReadSpec {
  const std::string& key;
  const NumberRule& rule;
  bool required;
  bool scalar_allowed;
};

template <>
struct SettingRead<double> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, double& v) {
    return r.number(k.key, v, k.rule, k.required);
  }
};

template <>
struct SettingRead<int> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, int& v) {
    return r.integer(k.key, v, k.rule, k.required);
  }
};

template <>
struct SettingRead<bool> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, bool& v) { return r.boolean(k.key, v, k.required); }
};

template <>
struct SettingRead<std::string> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, std::string& v) {
    return r.text(k.key, v, k.required);
  }
};

template <>
struct SettingRead<std::vector<std::string>> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, std::vector<std::string>& v) {
    return r.texts(k.key, v, k.required);
  }
};

template <>
struct SettingRead<Eigen::Vector3d> {
  static constexpr bool readable = true;
  static bool read(SettingReader& r, const ReadSpec& k, Eigen::Vector3d& v) {
    return r.vec3(k.key, v, k.rule, k.required, k.scalar_allowed);
  }
};

/// An optional value is set when its key is read.
template <typename T>
struct SettingRead<std::optional<T>> {
  static constexpr bool readable = SettingRead<T>::readable;
  static bool read(SettingReader& r, const ReadSpec& k, std::optional<T>& v) {
    T value{};
    if (!SettingRead<T>::read(r, k, value)) return false;
    v = value;
    return true;
  }
};

/// One declared field of a settings struct S: a setting the scene file gives, or a value the
/// scene fills from other settings (`derived`), as one line of every table of settings.
template <typename S>
struct SettingField {
  std::string name;   ///< path inside S: "supersampling", "shape.radii_mm", "organs[].name"
  std::string type;   ///< "number", "integer", "boolean", "text", "choice of a, b", ...
  std::string unit;   ///< "mm", "ms", ... ; empty for none
  std::string bounds; ///< the values the scene parser accepts, as text (from `rule` when it has one)
  std::string help;
  /// The numbers the scene parser accepts (a number's, a vector's components', an integer's);
  /// unset for a setting that is no number.
  std::optional<NumberRule> rule;
  bool required = false;       ///< the scene file must give it
  bool scalar_allowed = false; ///< 3 numbers: one number stands for all three
  /// Reads it from its key of the scene file's section (null: read by hand, or no plain key).
  std::function<bool(SettingReader&, const SettingField&, S&)> read;
  unsigned keys = no_cached_result; ///< the cached results it shapes (CacheKeys)
  bool derived = false;             ///< filled by the scene from other settings, not read from the file
  /// Written in its own section of the scene file and provenance.json; false for a key of
  /// another section (voxelization.gap_tissue is deformation.gap_tissue).
  bool in_section = true;
  std::function<std::string(const S&)> exact; ///< the value as a key writes it
  std::function<std::string(const S&)> shown; ///< the value as a reader reads it
  std::function<std::string(const S&)> json;  ///< the value as JSON (provenance.json)
  std::function<void(S&)> change;             ///< sets another value (tests change each in turn)
  /// The struct member this field is or lies in (its list or nested struct): every member of S
  /// must be the member of some field (settings_members() lists them all).
  std::function<const void*(const S&)> member;
};

/// Reads a declared field's key with its reader into `s`.
template <typename S>
bool read_field(SettingReader& reader, const SettingField<S>& f, S& s) {
  return f.read && f.read(reader, f, s);
}

/// The text of the fields of `s` that shape any of `keys`, one "name value" line each, in
/// declaration order: what a cache key hashes.
template <typename S>
std::string key_text(const std::vector<SettingField<S>>& fields, const S& s, unsigned keys) {
  std::string out;
  for (const SettingField<S>& f : fields)
    if (f.keys & keys) out += f.name + " " + f.exact(s) + "\n";
  return out;
}

/// Builds the declaration of one settings struct S, field by field.
template <typename S>
class SettingsDeclaration {
public:
  /// What every field added next shapes (CacheKeys), until the next call.
  SettingsDeclaration& shaping(unsigned keys) {
    m_keys = keys;
    return *this;
  }

  /// A setting held by member `m` of a type SettingValue knows, its accepted values described
  /// by `bounds` (empty: any; a name's rule, "a tissue").
  template <typename T>
  SettingsDeclaration& field(std::string name, T S::*m, std::string unit, std::string bounds,
                             std::string help) {
    SettingField<S> f = base(std::move(name), SettingValue<T>::type(), std::move(unit), std::move(bounds),
                             std::move(help), m);
    f.exact = [m](const S& s) { return SettingValue<T>::exact(s.*m); };
    f.shown = [m](const S& s) { return SettingValue<T>::shown(s.*m); };
    f.json = [m](const S& s) { return SettingValue<T>::json(s.*m); };
    f.change = [m](S& s) { SettingValue<T>::change(s.*m); };
    f.read = reader_of(m);
    m_fields.push_back(std::move(f));
    return *this;
  }

  /// A numeric setting (a number, an integer, 3 of them) whose accepted values are `rule`'s
  /// range: its bounds text is written from it, and the parser checks with it (in `unit`).
  template <typename T>
  SettingsDeclaration& field(std::string name, T S::*m, std::string unit, NumberRule rule, std::string help) {
    rule.unit = unit;
    const bool integer = SettingValue<T>::type().find("integer") != std::string::npos;
    const std::string bounds = rule.bounds_text(integer);
    field(std::move(name), m, std::move(unit), bounds, std::move(help));
    m_fields.back().rule = std::move(rule);
    return *this;
  }

  /// Marks the last field added as required: the scene file must give it.
  SettingsDeclaration& required() {
    m_fields.back().required = true;
    return *this;
  }

  /// Marks the last field added (3 numbers) as given by one number for all three as well.
  SettingsDeclaration& scalar_allowed() {
    m_fields.back().scalar_allowed = true;
    return *this;
  }

  /// Adds a condition beyond its rule to the last field's bounds text ("not zero").
  SettingsDeclaration& bounds_note(const std::string& note) {
    std::string& bounds = m_fields.back().bounds;
    bounds += (bounds.empty() ? "" : ", ") + note;
    return *this;
  }

  /// A setting of an enum type, by the names of its values.
  template <typename E>
  SettingsDeclaration& choice(std::string name, E S::*m, std::vector<std::pair<std::string, E>> choices,
                              std::string help) {
    std::string names;
    for (const auto& c : choices)
      names += (names.empty() ? "" : ", ") + c.first;
    SettingField<S> f = base(std::move(name), "choice of " + names, "", "", std::move(help), m);
    f.exact = f.shown = [m, choices](const S& s) {
      for (const auto& c : choices)
        if (c.second == s.*m) return c.first;
      return std::string("?");
    };
    f.json = [shown = f.shown](const S& s) { return json_string(shown(s)); };
    f.change = [m, choices](S& s) {
      for (std::size_t k = 0; k < choices.size(); ++k)
        if (choices[k].second == s.*m) {
          s.*m = choices[(k + 1) % choices.size()].second;
          return;
        }
    };
    f.read = [m, choices](SettingReader& reader, const SettingField<S>& field, S& s) {
      std::vector<std::string> accepted;
      for (const auto& c : choices)
        accepted.push_back(c.first);
      std::string given;
      if (!reader.choice(field.name, given, accepted, field.required)) return false;
      for (const auto& c : choices)
        if (c.first == given) s.*m = c.second;
      return true;
    };
    m_fields.push_back(std::move(f));
    return *this;
  }

  /// A setting written and changed by the given functions (a type SettingValue does not know).
  template <typename T>
  SettingsDeclaration& custom(std::string name, T S::*m, std::string type, std::string unit, std::string help,
                              std::function<std::string(const T&)> exact,
                              std::function<std::string(const T&)> shown, std::function<void(T&)> change) {
    SettingField<S> f = base(std::move(name), std::move(type), std::move(unit), "", std::move(help), m);
    f.exact = [m, exact](const S& s) { return exact(s.*m); };
    f.shown = [m, shown](const S& s) { return shown(s.*m); };
    f.json = [m](const S& s) { return SettingValue<T>::json(s.*m); };
    f.change = [m, change](S& s) { change(s.*m); };
    f.read = reader_of(m);
    m_fields.push_back(std::move(f));
    return *this;
  }

  /// Marks the last field added as derived: the scene fills it from `from`.
  SettingsDeclaration& derived_from(const std::string& from) {
    m_fields.back().derived = true;
    m_fields.back().help += " (set by the scene from " + from + ")";
    return *this;
  }

  /// Marks the last field added as a key of another section of the scene file, `key`.
  SettingsDeclaration& key_elsewhere(const std::string& key) {
    m_fields.back().in_section = false;
    m_fields.back().help += " (scene key " + key + ")";
    return *this;
  }

  /// Marks the last field added as no key of the scene file (a benchmark's switch).
  SettingsDeclaration& not_in_scene_file() {
    m_fields.back().in_section = false;
    return *this;
  }

  /// Every field of the nested struct held by member `m`, named "prefix.field"; the keys they
  /// shape are those of the nested declaration.
  template <typename N>
  SettingsDeclaration& nested(const std::string& prefix, N S::*m,
                              const std::vector<SettingField<N>>& fields) {
    for (const SettingField<N>& n : fields) {
      SettingField<S> f = relabel(prefix + "." + n.name, n, m);
      f.exact = [m, e = n.exact](const S& s) { return e(s.*m); };
      f.shown = [m, v = n.shown](const S& s) { return v(s.*m); };
      f.json = [m, j = n.json](const S& s) { return j(s.*m); };
      f.change = [m, c = n.change](S& s) { c(s.*m); };
      m_fields.push_back(std::move(f));
    }
    return *this;
  }

  /// A list of nested structs held by member `m`: its length (shaping `keys`), then every field
  /// of the nested struct over the list's elements, named "prefix[].field". A test's change of
  /// such a field changes the first element (made when the list is empty).
  template <typename N>
  SettingsDeclaration& list(const std::string& prefix, std::vector<N> S::*m, const std::string& help,
                            const std::vector<SettingField<N>>& fields) {
    unsigned all_keys = no_cached_result;
    for (const SettingField<N>& n : fields)
      all_keys |= n.keys;
    SettingField<S> count = base(prefix, "list", "", "", help, m);
    count.keys = all_keys;
    count.exact = count.shown = count.json = [m](const S& s) { return std::to_string((s.*m).size()); };
    count.change = [m](S& s) {
      if ((s.*m).empty())
        (s.*m).emplace_back();
      else
        (s.*m).pop_back();
    };
    m_fields.push_back(std::move(count));
    for (const SettingField<N>& n : fields) {
      SettingField<S> f = relabel(prefix + "[]." + n.name, n, m);
      f.exact = [m, e = n.exact](const S& s) {
        std::string out = "[";
        for (const N& element : s.*m)
          out += (out.size() > 1 ? " " : "") + e(element);
        return out + "]";
      };
      f.shown = [m, v = n.shown](const S& s) {
        std::string out;
        for (const N& element : s.*m)
          out += (out.empty() ? "" : "; ") + v(element);
        return "[" + out + "]";
      };
      f.json = [m, j = n.json](const S& s) {
        std::string out;
        for (const N& element : s.*m)
          out += (out.empty() ? "" : ",") + j(element);
        return "[" + out + "]";
      };
      f.change = [m, c = n.change](S& s) {
        if ((s.*m).empty()) (s.*m).emplace_back();
        c((s.*m).front());
      };
      m_fields.push_back(std::move(f));
    }
    return *this;
  }

  const std::vector<SettingField<S>>& fields() const { return m_fields; }

private:
  /// How a member of type T is read from its key; null for a type no plain key holds.
  template <typename T>
  static std::function<bool(SettingReader&, const SettingField<S>&, S&)> reader_of(T S::*m) {
    if constexpr (SettingRead<T>::readable) {
      return [m](SettingReader& reader, const SettingField<S>& f, S& s) {
        const NumberRule rule = f.rule.value_or(NumberRule{});
        return SettingRead<T>::read(reader, ReadSpec{f.name, rule, f.required, f.scalar_allowed}, s.*m);
      };
    } else {
      return nullptr;
    }
  }

  template <typename T>
  SettingField<S> base(std::string name, std::string type, std::string unit, std::string bounds,
                       std::string help, T S::*m) const {
    SettingField<S> f;
    f.name = std::move(name);
    f.type = std::move(type);
    f.unit = std::move(unit);
    f.bounds = std::move(bounds);
    f.help = std::move(help);
    f.keys = m_keys;
    f.member = [m](const S& s) -> const void* { return &(s.*m); };
    return f;
  }

  template <typename N, typename T>
  SettingField<S> relabel(std::string name, const SettingField<N>& n, T S::*m) const {
    SettingField<S> f = base(std::move(name), n.type, n.unit, n.bounds, n.help, m);
    f.rule = n.rule;
    f.keys = n.keys;
    f.derived = n.derived;
    f.in_section = n.in_section;
    return f;
  }

  unsigned m_keys = no_cached_result;
  std::vector<SettingField<S>> m_fields;
};

} // namespace phantasm
