#pragma once
// Strict whole-string number parsing for values read from files and command lines: no trailing
// junk, no locale, no NaN or infinity. Callers turn an empty result into an error that names
// the file, line and key they know about.
#include <optional>
#include <string_view>

namespace cvo::io {

/// The field as a finite double ("0.1", "-2", "8.315e-3", "+1"); nullopt otherwise.
std::optional<double> to_finite(std::string_view field);

/// The field as an integer ("5", "-3", "+7"); nullopt for "5.0", "1e3", overflow or junk.
std::optional<long long> to_integer(std::string_view field);

/// YAML 1.2's core booleans: "true"/"false" (also "True", "TRUE", ...); nullopt otherwise, so a
/// misspelt "ture" or a "1" meant as a number is an error rather than a silent false.
std::optional<bool> to_bool(std::string_view field);

}  // namespace cvo::io
