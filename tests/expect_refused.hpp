#pragma once
// Bad input is refused with one line naming the field: `call` must throw an InputError
// whose field() is `field`.
#include <gtest/gtest.h>

#include <string>

#include "learner/input_error.hpp"

namespace hbirl::testing {

template <class Call>
void expect_refused(Call&& call, const std::string& field) {
  try {
    call();
    ADD_FAILURE() << field << ": accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

}  // namespace hbirl::testing
