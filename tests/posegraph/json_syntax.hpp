#pragma once
// A strict JSON syntax check (RFC 8259) for a tool's --json output: exactly one value, white space
// around it at most. The project has no JSON library, and a regex over keys cannot tell that
// foreign text (a solver's message) landed in the middle of the object.
#include <cctype>
#include <cstddef>
#include <cstring>
#include <string_view>

namespace cvo::testing {

class JsonSyntax {
 public:
  static bool valid(std::string_view text) {
    JsonSyntax parser(text);
    if (!parser.value()) return false;
    parser.skip_space();
    return parser.at_ == text.size();
  }

 private:
  explicit JsonSyntax(std::string_view text) : text_(text) {}

  bool value() {
    skip_space();
    switch (peek()) {
      case '{': return object();
      case '[': return array();
      case '"': return string();
      case 't': return literal("true");
      case 'f': return literal("false");
      case 'n': return literal("null");
      default: return number();
    }
  }

  bool object() {
    ++at_;  // '{'
    if (next_is('}')) return true;
    do {
      skip_space();
      if (peek() != '"' || !string() || !next_is(':') || !value()) return false;
    } while (next_is(','));
    return next_is('}');
  }

  bool array() {
    ++at_;  // '['
    if (next_is(']')) return true;
    do {
      if (!value()) return false;
    } while (next_is(','));
    return next_is(']');
  }

  bool string() {
    ++at_;  // '"'
    while (at_ < text_.size()) {
      const char c = text_[at_++];
      if (c == '"') return true;
      if (static_cast<unsigned char>(c) < 0x20) return false;  // control characters must be escaped
      if (c == '\\' && !escape()) return false;
    }
    return false;
  }

  bool escape() {
    const char c = peek();
    ++at_;
    if (c == 'u') {
      for (int k = 0; k < 4; ++k, ++at_)
        if (!std::isxdigit(static_cast<unsigned char>(peek()))) return false;
      return true;
    }
    return c != '\0' && std::strchr("\"\\/bfnrt", c) != nullptr;
  }

  // -? (0 | [1-9][0-9]*) (. [0-9]+)? ([eE] [+-]? [0-9]+)?
  bool number() {
    accept('-');
    if (!accept('0') && !digits()) return false;
    if (accept('.') && !digits()) return false;
    if (accept('e') || accept('E')) {
      if (!accept('+')) accept('-');
      if (!digits()) return false;
    }
    return true;
  }

  bool digits() {
    const std::size_t start = at_;
    while (std::isdigit(static_cast<unsigned char>(peek()))) ++at_;
    return at_ > start;
  }

  bool literal(std::string_view word) {
    if (text_.substr(at_, word.size()) != word) return false;
    at_ += word.size();
    return true;
  }

  bool accept(char c) {
    if (peek() != c) return false;
    ++at_;
    return true;
  }

  bool next_is(char c) {
    skip_space();
    return accept(c);
  }

  void skip_space() {
    for (char c = peek(); c == ' ' || c == '\t' || c == '\r' || c == '\n'; c = peek()) ++at_;
  }

  [[nodiscard]] char peek() const { return at_ < text_.size() ? text_[at_] : '\0'; }

  std::string_view text_;
  std::size_t at_ = 0;
};

}  // namespace cvo::testing
