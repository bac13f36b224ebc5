#pragma once
// Test fixture that owns a fresh, empty directory per test,
// TMP/dsb_<suite>_<test>_<pid> (parameterised names sanitised), removed after the test; the
// databases, reports and logs a test writes go there. Fixtures that need more in SetUp call
// TempDirTest::SetUp() first.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace dsb::testing {

class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name =
        std::string("dsb_") + info->test_suite_name() + "_" + info->name() + "_" + std::to_string(::getpid());
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // a file of this test's directory
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
};

}  // namespace dsb::testing
