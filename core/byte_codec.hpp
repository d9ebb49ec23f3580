// Raw bytes of values and arrays for the caches a run keeps across runs (the anatomy cache, the
// reference cache): native-endian values, each array preceded by its dimensions, and a reader
// that refuses bytes that end early or hold arrays of another shape.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace phantasm {

/// Bytes that do not hold what they were read for (cut short, another format, other inputs).
class DamagedBytes : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class ByteWriter {
public:
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    m_bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void text(std::string_view s) {
    value(static_cast<std::uint64_t>(s.size()));
    m_bytes += s;
  }
  template <typename T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    value(static_cast<std::uint64_t>(v.size()));
    if (!v.empty()) m_bytes.append(reinterpret_cast<const char*>(v.data()), sizeof(T) * v.size());
  }
  template <typename Derived>
  void matrix(const Eigen::PlainObjectBase<Derived>& m) {
    value(static_cast<std::int64_t>(m.rows()));
    value(static_cast<std::int64_t>(m.cols()));
    if (m.size() > 0) {
      m_bytes.append(reinterpret_cast<const char*>(m.data()), sizeof(typename Derived::Scalar) * m.size());
    }
  }
  std::string take() { return std::move(m_bytes); }

private:
  std::string m_bytes;
};

class ByteReader {
public:
  /// @param what names the bytes in the messages of DamagedBytes ("organ geometry")
  ByteReader(std::string_view bytes, std::string what) : m_bytes(bytes), m_what(std::move(what)) {}
  template <typename T>
  T value() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, m_bytes.data() + m_at, sizeof v);
    m_at += sizeof v;
    return v;
  }
  std::string text() { return std::string(view()); }
  /// The next text() as a view into the bytes (no copy).
  std::string_view view() {
    const auto size = value<std::uint64_t>();
    need(size);
    const std::string_view s = m_bytes.substr(m_at, size);
    m_at += size;
    return s;
  }
  template <typename T>
  void array(std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto size = value<std::uint64_t>();
    if (size > (m_bytes.size() - m_at) / sizeof(T)) damaged("the bytes end early");
    v.resize(size);
    if (size > 0) std::memcpy(v.data(), m_bytes.data() + m_at, sizeof(T) * size);
    m_at += sizeof(T) * size;
  }
  template <typename Derived>
  void matrix(Eigen::PlainObjectBase<Derived>& m) {
    const auto rows = value<std::int64_t>();
    const auto cols = value<std::int64_t>();
    if (rows < 0 || cols < 0 ||
        (Derived::ColsAtCompileTime != Eigen::Dynamic && cols != Derived::ColsAtCompileTime) ||
        (Derived::RowsAtCompileTime != Eigen::Dynamic && rows != Derived::RowsAtCompileTime))
      damaged("an array of unexpected shape");
    const std::size_t size = sizeof(typename Derived::Scalar) * static_cast<std::size_t>(rows * cols);
    need(size);
    m.resize(rows, cols);
    if (size > 0) std::memcpy(m.data(), m_bytes.data() + m_at, size); // an empty array has no data()
    m_at += size;
  }
  bool done() const { return m_at == m_bytes.size(); }
  /// Throws DamagedBytes("<what>: <problem>").
  [[noreturn]] void damaged(const std::string& problem) const { throw DamagedBytes(m_what + ": " + problem); }

private:
  void need(std::size_t size) const {
    if (size > m_bytes.size() - m_at) damaged("the bytes end early");
  }
  std::string_view m_bytes;
  std::string m_what;
  std::size_t m_at = 0;
};

} // namespace phantasm
