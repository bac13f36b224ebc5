#pragma once
// Shared by the tests of every config struct: what its validate() says about a bad field.
#include <string>

#include <gtest/gtest.h>

#include "common/error.hpp"

namespace dsb::testing {

// the message of the ConfigError `config.validate()` throws, "valid" when it throws none
template <class Config>
std::string validation_message(const Config& config) {
  try {
    config.validate();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "valid";
}

// `config.validate()` throws a ConfigError whose message contains `names` (the field as the test
// spells it: "field 'x'", "'x'" or x)
template <class Config>
void expect_config_error_naming(const Config& config, const std::string& names) {
  try {
    config.validate();
    ADD_FAILURE() << "no ConfigError naming " << names;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
}

}  // namespace dsb::testing
