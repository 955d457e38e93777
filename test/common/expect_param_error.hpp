#pragma once
// Test helper shared by the parameter tests.
#include <gtest/gtest.h>

#include "common/params.hpp"

namespace alight::test {

/// Runs `fn`, which must throw ParamError, and returns it.
template <class Fn>
ParamError expect_param_error(Fn fn) {
  try {
    fn();
  } catch (const ParamError& e) {
    return e;
  }
  ADD_FAILURE() << "no ParamError thrown";
  return ParamError("", "", "", "");
}

}  // namespace alight::test
