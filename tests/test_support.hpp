#pragma once
// Helpers shared by the unit tests.

#include <doctest/doctest.h>

#include <exception>
#include <string>
#include <typeinfo>

#include "momentid/model.hpp"

namespace momentid::testing {

// A model from the project's models/ folder.
inline Model model_file(const std::string& name) {
  return parse_model_file(std::string(MOMENTID_SOURCE_DIR) + "/models/" + name);
}

// Runs `action` and returns the exception it throws, which must be exactly of type E. Fails the
// test case when `action` throws nothing, or something else.
template <class E, class Action>
E error_from(Action&& action) {
  try {
    action();
  } catch (const E& e) {
    if (typeid(e) != typeid(E)) FAIL("threw " << typeid(e).name() << ": " << e.what());
    return e;
  } catch (const std::exception& e) {
    FAIL("threw " << typeid(e).name() << " instead: " << e.what());
  } catch (...) {
    FAIL("threw something that is not a std::exception");
  }
  FAIL("threw nothing");
  throw;  // not reached: FAIL throws
}

}  // namespace momentid::testing
