#include "libcvo/core/session.hpp"

#include <algorithm>
#include <cstdio>

namespace cvo::core {

std::string session_name(SessionId session) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(session));
  return text;
}

bool is_robot_name(std::string_view name) {
  return !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '.' || ch == '-' ||
           ch == '_';
  });
}

std::string robot_name_error(std::string_view name) {
  if (is_robot_name(name)) return {};
  return "robot of " + std::to_string(name.size()) + " bytes is no robot name (" + std::string(kRobotNameRule) + ")";
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
