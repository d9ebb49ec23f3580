// The patch fit's height search (anatomy/patch_fit.cpp): where a target's surface crosses the
// line through a base point along a patch's normal, found one value at a time so that a patch's
// searches can run interleaved. In a header of its own for the fit and its tests.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace phantasm {

/// Height of the target above a base point b along unit normal n, within +-limit (NaN if none),
/// as a machine that asks for one value at a time: next() is the height h whose value, the
/// target's at b + h n, feed() takes next, until done(). A sign change is bracketed by stepping
/// outward from b, up and down in turn, then refined by regula falsi (Illinois variant). A
/// sample whose value exceeds the target's slope bound times the distance to the next samples on
/// its side settles their sign, so they are not evaluated: the bracket found, and its values,
/// are those of evaluating every step. Asking for values one at a time lets a patch's searches
/// run interleaved (height_searches): each its own numbers in its own order, so the same
/// heights as one search after another, while the processor overlaps their evaluations.
class HeightSearch {
public:
  HeightSearch(double slope_bound, double limit)
      : m_limit(limit), m_change_per_step(slope_bound * (limit / k_steps) * (1.0 + 1e-6)) {}

  bool done() const { return m_phase == Phase::done; }
  double next() const { return m_next; }
  /// The height found (NaN if none), once done().
  double height() const { return m_height; }

  /// The value at next().
  void feed(double value) {
    switch (m_phase) {
    case Phase::base:
      if (value == 0.0) return finish(0.0);
      m_up.value = m_down.value = m_lo_value = value;
      settle(m_up);
      settle(m_down);
      return march();
    case Phase::step: {
      Side& side = m_on_up ? m_up : m_down;
      if ((value > 0.0) != (side.value > 0.0)) {
        m_hi = m_next, m_hi_value = value;
        if (side.step == m_step - 1) {
          m_lo = side.h, m_lo_value = side.value;
          return refine();
        }
        // The last step evaluated on this side lies further back: the step before this one was
        // settled, its value not known.
        m_lo = side.sign * (m_limit * (m_step - 1) / k_steps);
        m_next = m_lo;
        m_phase = Phase::low;
        return;
      }
      side.step = m_step, side.h = m_next, side.value = value;
      settle(side);
      if (m_on_up) {
        m_on_up = false;
      } else {
        m_on_up = true;
        ++m_step;
      }
      return march();
    }
    case Phase::low: m_lo_value = value; return refine();
    case Phase::refine:
      if (value == 0.0) return finish(m_next);
      if ((value > 0.0) == (m_lo_value > 0.0)) {
        m_lo = m_next, m_lo_value = value;
        if (m_kept == -1) m_hi_value *= 0.5;
        m_kept = -1;
      } else {
        m_hi = m_next, m_hi_value = value;
        if (m_kept == 1) m_lo_value *= 0.5;
        m_kept = 1;
      }
      ++m_iteration;
      return refine();
    case Phase::done: return;
    }
  }

private:
  static constexpr int k_steps = 32;
  enum class Phase { base, step, low, refine, done };
  struct Side {
    double sign;           // +1 stepping up, -1 down
    int step = 0;          // the last step evaluated
    double h = 0.0, value; // its height and value
    int settled = 0;       // steps up to this one have that value's sign
  };

  void settle(Side& side) const {
    const double room = (std::abs(side.value) - 1e-12) / m_change_per_step;
    side.settled = side.step + (room > 0.0 ? static_cast<int>(std::min(room, double(k_steps))) : 0);
  }

  /// The next step to evaluate, up then down at each step number, skipping settled ones.
  void march() {
    for (; m_step <= k_steps; ++m_step) {
      if (m_on_up) {
        if (m_step > m_up.settled) return ask(m_up);
        m_on_up = false;
      }
      if (m_step > m_down.settled) return ask(m_down);
      m_on_up = true;
    }
    finish(std::nan(""));
  }

  void ask(const Side& side) {
    m_next = side.sign * (m_limit * m_step / k_steps);
    m_phase = Phase::step;
  }

  /// The next regula falsi point, or the bracket's middle once it is narrow enough.
  void refine() {
    if (m_iteration < 100 && std::abs(m_hi - m_lo) > 1e-12 * m_limit) {
      m_next = (m_lo * m_hi_value - m_hi * m_lo_value) / (m_hi_value - m_lo_value);
      m_phase = Phase::refine;
      return;
    }
    finish(0.5 * (m_lo + m_hi));
  }

  void finish(double height) {
    m_height = height;
    m_phase = Phase::done;
  }

  double m_limit, m_change_per_step;
  Phase m_phase = Phase::base;
  double m_next = 0.0, m_height = 0.0;
  Side m_up{1.0, 0, 0.0, 0.0}, m_down{-1.0, 0, 0.0, 0.0};
  int m_step = 1;      // the step number being marched
  bool m_on_up = true; // on the upper side at that step
  double m_lo = 0.0, m_lo_value = 0.0, m_hi = 0.0, m_hi_value = 0.0;
  int m_iteration = 0, m_kept = 0; // regula falsi's count, and the end kept last (-1 lo, 1 hi)
};

/// The target's value along base point b + h n.
template <class Value>
inline double value_along(const Value& value, const Eigen::Vector3d& b, const Eigen::Vector3d& n, double h) {
  return value(b + h * n);
}

template <class Value>
double height_search(const Value& value, double slope_bound, const Eigen::Vector3d& b,
                     const Eigen::Vector3d& n, double limit) {
  HeightSearch search(slope_bound, limit);
  while (!search.done())
    search.feed(value_along(value, b, n, search.next()));
  return search.height();
}

/// height_search from each of `bases` along n into `heights`, the searches interleaved: each
/// round feeds every unfinished search one value.
template <class Value>
void height_searches(const Value& value, double slope_bound, const std::vector<Eigen::Vector3d>& bases,
                     const Eigen::Vector3d& n, double limit, std::vector<HeightSearch>& searches,
                     std::vector<std::uint32_t>& running, std::vector<double>& values,
                     std::vector<double>& heights) {
  searches.assign(bases.size(), HeightSearch(slope_bound, limit));
  running.resize(bases.size());
  for (std::size_t k = 0; k < bases.size(); ++k)
    running[k] = static_cast<std::uint32_t>(k);
  heights.resize(bases.size());
  values.resize(bases.size());
  while (!running.empty()) {
    // The values first, in a loop of their own (no branching on the searches' states), then
    // each search's step.
    for (std::size_t r = 0; r < running.size(); ++r)
      values[r] = value_along(value, bases[running[r]], n, searches[running[r]].next());
    std::size_t kept = 0;
    for (std::size_t r = 0; r < running.size(); ++r) {
      const std::uint32_t k = running[r];
      HeightSearch& search = searches[k];
      search.feed(values[r]);
      if (search.done()) {
        heights[k] = search.height();
      } else {
        running[kept++] = k;
      }
    }
    running.resize(kept);
  }
}

} // namespace phantasm
