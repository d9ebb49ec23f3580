#pragma once

#include "core/error.hpp"

#include <functional>
#include <string>

namespace phantasm::testing {

/// The message of the InputError an action throws, or "no error".
inline std::string input_error_message(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& error) {
    return error.what();
  }
  return "no error";
}

} // namespace phantasm::testing
