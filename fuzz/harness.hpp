#pragma once
// What every harness shares: the libFuzzer entry point's signature, and the one rule of what an
// input may do — be refused the way the parser documents (nullopt, io::InputError and its
// subclasses, std::invalid_argument) — while anything else (another exception, a sanitizer report,
// a crash) escapes to libFuzzer, or to the replay driver, as a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/io/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace cvo::fuzz {

/// Runs `parse` and swallows exactly the documented refusals.
template <class F>
void expect_refusal_or_success(F&& parse) {
  try {
    parse();
  } catch (const io::InputError&) {
  } catch (const std::invalid_argument&) {
  }
}

/// A finding that is not a crash by itself (a broken documented guarantee): says which, then
/// aborts, so libFuzzer keeps the input as a reproducer.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz: %s\n", what.c_str());
  std::abort();
}

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// The parts of an input separated by lines "---", for parsers that read several files at once.
std::vector<std::string> split_parts(std::string_view text);

/// An empty folder of this process's own for parsers that take files: emptied at every call,
/// removed at exit. On /dev/shm when there is one, so the keyframe store's fsyncs cost nothing.
const std::filesystem::path& scratch_dir();

/// Writes `bytes` to `file` (replacing it).
void write_file(const std::filesystem::path& file, std::string_view bytes);

}  // namespace cvo::fuzz
