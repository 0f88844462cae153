#include "tools/cvo-vocabulary/image_list.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::tools {
namespace {

namespace fs = std::filesystem;

bool is_image_name(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* known : {".png", ".jpg", ".jpeg", ".webp", ".bmp", ".ppm", ".pgm", ".tif", ".tiff"})
    if (ext == known) return true;
  return false;
}

// "timestamp path" lines; paths relative to the index's folder.
std::vector<fs::path> tum_colour_images(const fs::path& index) {
  std::ifstream in(index);
  if (!in) throw io::InputError(index, "cannot open");
  std::vector<fs::path> images;
  io::for_each_data_line(in, index, [&](std::size_t line, const std::vector<std::string>& fields) {
    if (fields.size() < 2) throw io::InputError(index, line, "expected 'timestamp path'");
    images.push_back(index.parent_path() / fields[1]);
  });
  return images;
}

std::vector<fs::path> image_files(const fs::path& dir) {
  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.is_regular_file() && is_image_name(entry.path())) images.push_back(entry.path());
  std::sort(images.begin(), images.end());  // directory order is arbitrary
  return images;
}

}  // namespace

std::vector<fs::path> list_images(const std::vector<fs::path>& inputs, std::size_t every) {
  std::vector<fs::path> out;
  for (const fs::path& input : inputs) {
    std::error_code ec;
    const auto status = fs::status(input, ec);
    if (!fs::exists(status)) throw io::InputError(input, "no such file or folder");
    if (!fs::is_directory(status)) {
      out.push_back(input);
      continue;
    }
    const bool tum = fs::exists(input / "rgb.txt");
    const std::vector<fs::path> all = tum ? tum_colour_images(input / "rgb.txt") : image_files(input);
    if (all.empty())
      throw io::InputError(tum ? input / "rgb.txt" : input, tum ? "lists no images" : "no image files in the folder");
    for (std::size_t i = 0; i < all.size(); i += every) out.push_back(all[i]);
  }
  return out;
}

}  // namespace cvo::tools
