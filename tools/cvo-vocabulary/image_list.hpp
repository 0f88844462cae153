#pragma once
// The training images named on cvo-vocabulary's command line.
#include <cstddef>
#include <filesystem>
#include <vector>

namespace cvo::tools {

/// Expands each input: an image file is itself; a folder with rgb.txt (TUM layout) gives every
/// `every`-th colour image it lists, from the first; any other folder every `every`-th image file
/// in it (by name; .png .jpg .jpeg .webp .bmp .ppm .pgm .tif .tiff; not recursive).
/// Throws io::InputError naming the path for a missing input, a malformed rgb.txt or a folder
/// without images.
std::vector<std::filesystem::path> list_images(const std::vector<std::filesystem::path>& inputs, std::size_t every);

}  // namespace cvo::tools
