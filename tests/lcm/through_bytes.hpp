#pragma once
// A message through its wire form: encoded, then decoded as a receiver would (decode.hpp), the
// decoding expected to succeed.
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "libcvo/lcm/decode.hpp"

namespace cvo::lcm {

template <class T>
std::optional<T> through_bytes(const T& message) {
  const auto bytes = encode(message);
  std::string error;
  auto decoded = decode<T>(bytes.data(), static_cast<int>(bytes.size()), &error);
  EXPECT_TRUE(decoded) << error;
  return decoded;
}

}  // namespace cvo::lcm
