#include "libcvo/core/session.hpp"

#include <cstdio>

namespace cvo::core {

std::string session_name(SessionId session) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(session));
  return text;
}

}  // namespace cvo::core
