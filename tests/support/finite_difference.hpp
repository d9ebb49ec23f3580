#pragma once

// Central finite differences for the derivative tests, and the comparison of an analytic
// derivative with them. Every gradient, Jacobian and Hessian check of the suite goes through
// these, so step and error conventions are the same everywhere: central differences
// (f(x + h e_i) - f(x - h e_i)) / 2h, truncation error O(h^2), and errors measured as the
// largest coordinate difference relative to the largest coordinate of the estimate.

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>
#include <vector>

namespace phantasm::testing {

namespace detail {

/// A scalar as itself, an Eigen expression as its evaluated object.
template <class Value>
auto evaluated(const Value& value) {
  if constexpr (std::is_arithmetic_v<Value>)
    return static_cast<double>(value);
  else
    return value.eval();
}

} // namespace detail

/// Central difference of f along one coordinate of x.
/// @param f function of an object of x's type, returning a scalar or an Eigen object
/// @param x the point (any dense Eigen vector or matrix)
/// @param i the coordinate, as a column-major index into x
/// @param h the step, in x's units
/// @return (f(x + h e_i) - f(x - h e_i)) / 2h, of f's value type
template <class Function, class Point>
auto central_difference(const Function& f, const Point& x, Eigen::Index i, double h) {
  typename Point::PlainObject plus = x, minus = x;
  plus.data()[i] += h;
  minus.data()[i] -= h;
  return detail::evaluated((f(plus) - f(minus)) / (2.0 * h));
}

/// Central difference of f along a direction: (f(x + h d) - f(x - h d)) / 2h.
/// @param f function of an object of x's type, returning a scalar or an Eigen object
/// @param x the point, @param direction a displacement of x's shape (unit length for a
/// directional derivative), @param h the step along it
template <class Function, class Point, class Direction>
auto directional_difference(const Function& f, const Point& x, const Direction& direction, double h) {
  const typename Point::PlainObject plus = x + h * direction, minus = x - h * direction;
  return detail::evaluated((f(plus) - f(minus)) / (2.0 * h));
}

/// The gradient of a scalar function by central differences in every coordinate.
/// @param f scalar function of an object of x's type
/// @param x the point (any dense Eigen vector or matrix), @param h the step in x's units
/// @return d f / d x, of x's shape
template <class Function, class Point>
typename Point::PlainObject central_difference_gradient(const Function& f, const Point& x, double h) {
  typename Point::PlainObject gradient(x.rows(), x.cols());
  for (Eigen::Index i = 0; i < x.size(); ++i)
    gradient.data()[i] = central_difference(f, x, i, h);
  return gradient;
}

/// Some coordinates of the gradient of a scalar function (for large points where every
/// coordinate would cost too much).
/// @param coordinates column-major indices into x
/// @return d f / d x at those coordinates, in their order
template <class Function, class Point>
Eigen::VectorXd central_difference_gradient(const Function& f, const Point& x, double h,
                                            const std::vector<Eigen::Index>& coordinates) {
  Eigen::VectorXd gradient(static_cast<Eigen::Index>(coordinates.size()));
  for (std::size_t k = 0; k < coordinates.size(); ++k)
    gradient[static_cast<Eigen::Index>(k)] = central_difference(f, x, coordinates[k], h);
  return gradient;
}

/// The Jacobian of an Eigen-valued function by central differences.
/// @param f function of an object of x's type returning an Eigen vector or matrix
/// @return (number of values of f) x (number of coordinates of x): column i holds the
/// column-major derivative of f along coordinate i of x
template <class Function, class Point>
Eigen::MatrixXd central_difference_jacobian(const Function& f, const Point& x, double h) {
  Eigen::MatrixXd jacobian;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const auto column = central_difference(f, x, i, h);
    if (i == 0) jacobian.resize(column.size(), x.size());
    jacobian.col(i) = Eigen::Map<const Eigen::VectorXd>(column.data(), column.size());
  }
  return jacobian;
}

/// Largest coordinate difference between an analytic derivative and its finite-difference
/// estimate, relative to the estimate's largest coordinate or `scale_floor`, whichever is larger.
template <class Analytic, class Numeric>
double relative_error(const Eigen::MatrixBase<Analytic>& analytic, const Eigen::MatrixBase<Numeric>& numeric,
                      double scale_floor = 0.0) {
  const double scale = std::max(numeric.cwiseAbs().maxCoeff(), scale_floor);
  return (analytic.derived() - numeric.derived()).cwiseAbs().maxCoeff() / scale;
}

/// Passes when relative_error(analytic, numeric, scale_floor) <= tolerance; the message names
/// the worst coordinate.
/// @param tolerance relative error allowed (truncation O(h^2) plus rounding O(eps f / h))
/// @param scale_floor smallest scale the error is measured against, in the derivative's units
/// (for derivatives that may vanish, or to measure against a known magnitude)
template <class Analytic, class Numeric>
::testing::AssertionResult matches_finite_differences(const Eigen::MatrixBase<Analytic>& analytic,
                                                      const Eigen::MatrixBase<Numeric>& numeric,
                                                      double tolerance, double scale_floor = 0.0) {
  if (analytic.rows() != numeric.rows() || analytic.cols() != numeric.cols()) {
    return ::testing::AssertionFailure()
           << "analytic derivative is " << analytic.rows() << " x " << analytic.cols()
           << ", finite differences " << numeric.rows() << " x " << numeric.cols();
  }
  const double error = relative_error(analytic, numeric, scale_floor);
  if (error <= tolerance) return ::testing::AssertionSuccess();
  Eigen::Index row = 0, col = 0;
  (analytic.derived() - numeric.derived()).cwiseAbs().maxCoeff(&row, &col);
  std::ostringstream message;
  message.precision(10);
  message << "relative error " << error << " above " << tolerance << ": at (" << row << ", " << col
          << ") analytic " << analytic.derived()(row, col) << ", finite differences "
          << numeric.derived()(row, col);
  return ::testing::AssertionFailure() << message.str();
}

/// The scalar form: |analytic - numeric| <= tolerance * max(|numeric|, scale_floor).
inline ::testing::AssertionResult matches_finite_differences(double analytic, double numeric,
                                                             double tolerance, double scale_floor = 0.0) {
  return matches_finite_differences(Eigen::Matrix<double, 1, 1>(analytic),
                                    Eigen::Matrix<double, 1, 1>(numeric), tolerance, scale_floor);
}

} // namespace phantasm::testing
