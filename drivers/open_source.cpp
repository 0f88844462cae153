#include "drivers/open_source.hpp"

#include <filesystem>

#include "drivers/lcm_source.hpp"
#include "drivers/oni_file.hpp"
#include "drivers/openni2_source.hpp"
#include "drivers/tum_source.hpp"
#include "drivers/v4l2_source.hpp"

namespace cvo::drivers {

std::unique_ptr<FrameSource> open_source(std::string_view spec, const SourceOptions& options) {
  const auto colon = spec.find(':');
  const std::string_view scheme = spec.substr(0, colon);
  const std::string_view rest = colon == std::string_view::npos ? std::string_view{} : spec.substr(colon + 1);
  if (colon != std::string_view::npos) {
    if (scheme == "tum") return open_tum(std::filesystem::path(rest), options);
    if (scheme == "lcm") return open_lcm(rest, options);
    if (scheme == "openni2") return open_openni2(rest, options);
    if (scheme == "v4l2") return open_v4l2(rest, options);
  }
  throw SourceError(std::string(spec),
                    "not a frame source; valid sources: tum:DIR, lcm:URL, openni2:URI, v4l2:COLOUR,DEPTH");
}

bool names_device(std::string_view spec) {
  if (spec.starts_with("v4l2:")) return true;
  if (!spec.starts_with("openni2:")) return false;
  const std::string uri(spec.substr(8));
  return uri.starts_with("cvo-virtual:") || !is_oni_path(uri);
}

}  // namespace cvo::drivers
