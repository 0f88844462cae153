#pragma once
// Shorthands for the ReadResults sources return: ReadResult is an aggregate, and -Wextra wants
// every field of a braced initializer spelled out.
#include <string>
#include <utility>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

inline ReadResult result(ReadStatus status, std::string message = {}) {
  return {status, BadInput::kContent, std::move(message)};
}

inline ReadResult bad_input(BadInput kind, std::string message) {
  return {ReadStatus::kBadInput, kind, std::move(message)};
}

}  // namespace cvo::drivers
