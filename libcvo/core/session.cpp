#include "libcvo/core/session.hpp"

#include <cstdio>

namespace cvo::core {

std::string session_name(SessionId session) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(session));
  return text;
}

const char* to_string(LocalizationState state) {
  switch (state) {
    case LocalizationState::kLocalizing: return "localizing";
    case LocalizationState::kLocalized: return "localized";
    case LocalizationState::kLost: return "lost";
  }
  return "unknown";
}

}  // namespace cvo::core
