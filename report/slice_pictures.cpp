#include "report/slice_pictures.hpp"

#include "io/preview_png.hpp"

#include <algorithm>
#include <cmath>

namespace phantasm {

SliceMontage::SliceMontage(const Eigen::Vector3i& dims) : m_dims(dims) {
  const std::int64_t nx = dims.x(), ny = dims.y(), nz = dims.z();
  m_width = static_cast<int>(nx + nx + ny);
  m_height = static_cast<int>(std::max(ny, nz));
  m_voxel.assign(static_cast<std::size_t>(m_width) * static_cast<std::size_t>(m_height), -1);
  auto index = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + nx * (j + ny * k); };
  auto at = [&](std::int64_t x, std::int64_t y) -> std::int64_t& {
    return m_voxel[static_cast<std::size_t>(y * m_width + x)];
  };
  for (std::int64_t j = 0; j < ny; ++j)
    for (std::int64_t i = 0; i < nx; ++i)
      at(i, j) = index(i, j, nz / 2);
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t i = 0; i < nx; ++i)
      at(nx + i, k) = index(i, ny / 2, k);
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      at(2 * nx + j, k) = index(nx / 2, j, k);
}

int SliceMontage::panel(int x) const {
  return x < m_dims.x() ? 0 : x < 2 * m_dims.x() ? 1 : 2;
}

namespace {

/// Pixels of a montage, `components` bytes each, from a function of (x, y) that fills them.
template <typename Fill>
std::string montage_png(const SliceMontage& montage, int components, Fill fill) {
  std::vector<unsigned char> pixels(static_cast<std::size_t>(montage.width()) *
                                        static_cast<std::size_t>(montage.height()) *
                                        static_cast<std::size_t>(components),
                                    0);
  for (int y = 0; y < montage.height(); ++y)
    for (int x = 0; x < montage.width(); ++x)
      fill(x, y, &pixels[(static_cast<std::size_t>(y) * montage.width() + x) * components]);
  return encode_png(montage.width(), montage.height(), components, pixels);
}

unsigned char byte_of(double fraction) {
  return static_cast<unsigned char>(std::lround(255.0 * std::clamp(fraction, 0.0, 1.0)));
}

/// Piecewise-linear colour through `stops` (RGB, equally spaced) at t in [0, 1].
template <std::size_t N>
std::array<unsigned char, 4> through(const std::array<std::array<double, 3>, N>& stops, double t) {
  const double s = std::clamp(t, 0.0, 1.0) * static_cast<double>(N - 1);
  const std::size_t a = std::min(static_cast<std::size_t>(s), N - 2);
  const double f = s - static_cast<double>(a);
  std::array<unsigned char, 4> rgba{};
  for (int c = 0; c < 3; ++c)
    rgba[c] = byte_of(stops[a][c] + f * (stops[a + 1][c] - stops[a][c]));
  rgba[3] = 255;
  return rgba;
}

// A perceptually ordered scale (dark blue, teal, green, yellow; close to matplotlib's viridis).
constexpr std::array<std::array<double, 3>, 5> k_magnitude_stops = {{{0.267, 0.005, 0.329},
                                                                     {0.230, 0.322, 0.546},
                                                                     {0.128, 0.567, 0.551},
                                                                     {0.369, 0.789, 0.383},
                                                                     {0.993, 0.906, 0.144}}};
// Blue (shrinking), white (no change), red (growing).
constexpr std::array<std::array<double, 3>, 3> k_ratio_stops = {
    {{0.17, 0.35, 0.85}, {1.0, 1.0, 1.0}, {0.85, 0.15, 0.12}}};

} // namespace

std::string grey_slices_png(const SliceMontage& montage, const std::vector<double>& values) {
  std::vector<double> shown;
  shown.reserve(static_cast<std::size_t>(montage.width()) * montage.height());
  for (int y = 0; y < montage.height(); ++y)
    for (int x = 0; x < montage.width(); ++x)
      if (const std::int64_t v = montage.voxel(x, y); v >= 0 && std::isfinite(values[v]))
        shown.push_back(values[v]);
  double low = 0.0, high = 1.0;
  if (!shown.empty()) {
    auto rank = [&](double q) {
      const auto at = shown.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(shown.size() - 1));
      std::nth_element(shown.begin(), at, shown.end());
      return *at;
    };
    low = std::min(0.0, rank(0.005));
    high = rank(0.995);
    if (!(high > low)) high = low + 1.0;
  }
  return montage_png(montage, 1, [&](int x, int y, unsigned char* pixel) {
    const std::int64_t v = montage.voxel(x, y);
    if (v >= 0 && std::isfinite(values[v])) pixel[0] = byte_of((values[v] - low) / (high - low));
  });
}

std::string contour_slices_png(const SliceMontage& montage, const std::vector<std::int32_t>& labels) {
  auto label_at = [&](int x, int y) -> std::int64_t {
    if (x < 0 || y < 0 || x >= montage.width() || y >= montage.height()) return -1;
    const std::int64_t v = montage.voxel(x, y);
    return v < 0 ? -1 : labels[v];
  };
  return montage_png(montage, 4, [&](int x, int y, unsigned char* pixel) {
    const std::int64_t own = label_at(x, y);
    if (own <= 0) return; // background and outside the panels: the boundary is drawn inside organs
    const int panel = montage.panel(x);
    bool edge = false;
    for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const int nx = x + dx, ny = y + dy;
      const bool same_panel = nx >= 0 && nx < montage.width() && montage.panel(nx) == panel;
      if (!same_panel || label_at(nx, ny) != own) edge = true;
    }
    if (!edge) return;
    // Well-separated hues by the golden angle, bright enough to show on grey.
    const double hue = std::fmod(static_cast<double>(own) * 0.618033988749895, 1.0) * 6.0;
    const double f = hue - std::floor(hue);
    const int sector = static_cast<int>(hue) % 6;
    const double q = 1.0 - f, t = f;
    const std::array<std::array<double, 3>, 6> rgb = {
        {{1, t, 0}, {q, 1, 0}, {0, 1, t}, {0, q, 1}, {t, 0, 1}, {1, 0, q}}};
    for (int c = 0; c < 3; ++c)
      pixel[c] = byte_of(0.25 + 0.75 * rgb[sector][c]);
    pixel[3] = 255;
  });
}

std::array<unsigned char, 4> ColourScale::colour(double value) const {
  if (kind == Kind::magnitude) {
    const double t = high > low ? (value - low) / (high - low) : 0.0;
    std::array<unsigned char, 4> rgba = through(k_magnitude_stops, t);
    rgba[3] = t < 0.02 ? 0 : 200;
    return rgba;
  }
  if (!(value > 0.0)) return {255, 0, 255, 255};
  const double log_low = std::log(std::max(low, 1e-6)), log_high = std::log(std::max(high, low * 1.000001));
  const double t = (std::log(value) - log_low) / (log_high - log_low);
  std::array<unsigned char, 4> rgba = through(k_ratio_stops, t);
  rgba[3] = std::abs(value - 1.0) < 0.01 ? 0 : 200;
  return rgba;
}

std::string colour_slices_png(const SliceMontage& montage, const std::vector<double>& values,
                              const ColourScale& scale) {
  return montage_png(montage, 4, [&](int x, int y, unsigned char* pixel) {
    const std::int64_t v = montage.voxel(x, y);
    if (v < 0 || !std::isfinite(values[v])) return;
    const std::array<unsigned char, 4> rgba = scale.colour(values[v]);
    std::copy(rgba.begin(), rgba.end(), pixel);
  });
}

std::string colour_bar_png(const ColourScale& scale, int width) {
  const int height = 14;
  std::vector<unsigned char> pixels(static_cast<std::size_t>(width) * height * 3);
  for (int x = 0; x < width; ++x) {
    const double t = (x + 0.5) / width;
    const double value = scale.kind == ColourScale::Kind::magnitude
                             ? scale.low + t * (scale.high - scale.low)
                             : scale.low * std::pow(scale.high / scale.low, t);
    std::array<unsigned char, 4> rgba = scale.colour(value);
    if (scale.kind == ColourScale::Kind::magnitude) rgba = through(k_magnitude_stops, t);
    for (int y = 0; y < height; ++y)
      std::copy(rgba.begin(), rgba.begin() + 3, &pixels[(static_cast<std::size_t>(y) * width + x) * 3]);
  }
  return encode_png(width, height, 3, pixels);
}

} // namespace phantasm
