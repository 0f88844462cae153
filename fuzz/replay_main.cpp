// The replay driver of the normal build: runs a harness's LLVMFuzzerTestOneInput once on every file
// of the folders given (seeds and reproducers), as libFuzzer would replay them, so a parser change
// that brings back a fixed crash fails an ordinary CTest case without clang or libFuzzer. A finding
// aborts (sanitizers are not needed for the asserted guarantees; the asan preset adds them). No
// input at all replays nothing: exit 77, CTest's Skipped, never a pass.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz/harness.hpp"

int main(int argc, char** argv) {
  std::vector<std::filesystem::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path dir = argv[i];
    if (!std::filesystem::is_directory(dir)) {
      std::fprintf(stderr, "replay: %s is not a folder\n", dir.c_str());
      return 2;
    }
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
      if (entry.is_regular_file() && entry.path().filename() != "README.md") inputs.push_back(entry.path());
  }
  if (inputs.empty()) {
    std::printf("replay: skipped: no input in the folders given\n");
    return 77;
  }
  std::sort(inputs.begin(), inputs.end());  // a stable order, so a failing run names the same file first
  for (const auto& file : inputs) {
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) {
      std::fprintf(stderr, "replay: cannot read %s\n", file.c_str());
      return 2;
    }
    std::fprintf(stderr, "replay: %s\n", file.c_str());  // the last one named is the one that crashed
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("replay: %zu inputs, no finding\n", inputs.size());
  return 0;
}
