#pragma once
// Runs one of the built command-line tools the way a user's script would, capturing stdout,
// stderr and the exit code: the CLI tests check the contracts others script against.
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace cvo::testing {

struct ToolRun {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Waits until `file` contains `text` (a daemon's stderr saying it got somewhere), at most `timeout`;
/// whether it does.
inline bool wait_for_text(const std::filesystem::path& file, const std::string& text,
                          std::chrono::milliseconds timeout) {
  for (const auto until = std::chrono::steady_clock::now() + timeout; std::chrono::steady_clock::now() < until;) {
    if (slurp(file).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return slurp(file).find(text) != std::string::npos;
}

/// The first "key" in document order, depth first, or nullptr.
inline const nlohmann::ordered_json* find_key(const nlohmann::ordered_json& json, const std::string& key) {
  if (json.is_object())
    for (const auto& [name, value] : json.items()) {
      if (name == key) return &value;
      if (const auto* inner = find_key(value, key)) return inner;
    }
  if (json.is_array())
    for (const auto& value : json)
      if (const auto* inner = find_key(value, key)) return inner;
  return nullptr;
}

/// The value of "key" in a tool's JSON output (the first one, nested objects included) as JSON
/// text: a number, null, a quoted string, '[]' / '{}' when empty, '[' / '{' for an array / object; "<missing>" when
/// absent, "<not JSON>" when the text does not parse.
inline std::string json_value(const std::string& text, const std::string& key) {
  const auto json = nlohmann::ordered_json::parse(text, nullptr, false);
  if (json.is_discarded()) return "<not JSON>";
  const auto* value = find_key(json, key);
  if (value == nullptr) return "<missing>";
  if (value->is_array()) return value->empty() ? "[]" : "[";
  if (value->is_object()) return value->empty() ? "{}" : "{";
  return value->dump();
}

/// Single-quoted for the shell. Built with append(): GCC 12 warns falsely (-Wrestrict) on chained
/// operator+ of short strings.
inline std::string quoted(const std::filesystem::path& p) { return std::string("'").append(p.string()).append("'"); }

/// Runs `program <args>`; stderr goes through a file in `scratch` (a folder the test owns).
inline ToolRun run_program(const std::filesystem::path& program, const std::string& args,
                           const std::filesystem::path& scratch) {
  const auto err = scratch / (program.filename().string() + ".stderr.txt");
  const std::string command = quoted(program) + " " + args + " 2>" + quoted(err);
  ToolRun r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) r.out.append(buf, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err);
  return r;
}

/// Runs CVO_TOOLS_DIR/<tool> <args>, as run_program.
inline ToolRun run_tool(const std::string& tool, const std::string& args, const std::filesystem::path& scratch) {
  return run_program(std::filesystem::path(CVO_TOOLS_DIR) / tool, args, scratch);
}

}  // namespace cvo::testing
