#pragma once
// Shorthands for the ReadResults sources return: ReadResult is an aggregate, and -Wextra wants
// every field of a braced initializer spelled out.
#include <string>
#include <utility>

#include "drivers/frame_source.hpp"

namespace cvo::drivers {

inline ReadResult result(ReadStatus status, std::string message = {}) {
  return {status, core::BadKind::kContent, std::move(message)};
}

inline ReadResult bad_input(core::BadKind kind, std::string message) {
  return {ReadStatus::kBadInput, kind, std::move(message)};
}

}  // namespace cvo::drivers
