// The message of a call that should fail, for tests that compare messages:
//   EXPECT_EQ(ErrorText([&] { ParseNumber("1e-400", "--x"); }), "--x: ... underflows to 0)");
// The what() of the exception of type E that fn throws, or `none` when it
// throws nothing (another exception type propagates and fails the test).
#ifndef ESTLAB_TESTS_ERROR_TEXT_H_
#define ESTLAB_TESTS_ERROR_TEXT_H_

#include <string>

#include "src/core/types.h"

namespace estlab::testing {

template <class E = InputError, class Fn>
std::string ErrorText(Fn&& fn, const std::string& none = "") {
  try {
    fn();
  } catch (const E& e) {
    return e.what();
  }
  return none;
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_ERROR_TEXT_H_
