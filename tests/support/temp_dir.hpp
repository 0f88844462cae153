#pragma once
// A fresh folder under the system temp dir for one test, removed with everything in it at the end.
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

namespace cvo::test {

class TempDir {
 public:
  explicit TempDir(const std::string& name_hint = "cvo_test") {
    // Tests run as parallel processes: the test's name plus a random number keeps folders apart.
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::string test = info ? std::string(info->test_suite_name()) + "_" + info->name() : "none";
    path_ = std::filesystem::temp_directory_path() /
            (name_hint + "_" + test + "_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;  // never throw from a destructor; a leftover temp folder is harmless
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

  /// Writes a text file below the folder (creating subfolders) and returns its path.
  std::filesystem::path write(const std::filesystem::path& relative, const std::string& text) const {
    const auto file = path_ / relative;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace cvo::test
