#include "fuzz/harness.hpp"

#include <cstdlib>
#include <fstream>
#include <system_error>

namespace cvo::fuzz {

std::vector<std::string> split_parts(std::string_view text) {
  static constexpr std::string_view kSeparator = "\n---\n";
  std::vector<std::string> parts;
  for (;;) {
    const auto at = text.find(kSeparator);
    // Each part keeps its last line's newline, as the file it stands for would.
    parts.emplace_back(text.substr(0, at == std::string_view::npos ? text.size() : at + 1));
    if (at == std::string_view::npos) return parts;
    text.remove_prefix(at + kSeparator.size());
  }
}

namespace {
struct Scratch {
  std::filesystem::path dir;
  Scratch() {
    const char* tmpdir = std::getenv("TMPDIR");
    std::string base = tmpdir != nullptr && *tmpdir != '\0'        ? tmpdir
                       : std::filesystem::is_directory("/dev/shm") ? "/dev/shm"
                                                                   : "/tmp";
    std::string pattern = base + "/cvo-fuzz-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) fail("cannot create a scratch folder under " + base);
    dir = pattern;
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};
}  // namespace

const std::filesystem::path& scratch_dir() {
  static const Scratch scratch;
  for (const auto& entry : std::filesystem::directory_iterator(scratch.dir)) std::filesystem::remove_all(entry);
  return scratch.dir;
}

void write_file(const std::filesystem::path& file, std::string_view bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) fail("cannot write " + file.string());
}

}  // namespace cvo::fuzz
