#include "libcvo/auth/sender.hpp"

#include <sodium.h>
#include <unistd.h>

#include <cstdlib>

#include <fstream>
#include <iterator>

#include "libcvo/auth/key.hpp"

namespace cvo::auth {
namespace {

std::string read_all(const char* file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void hash_field(crypto_generichash_state& state, std::string_view field) {
  const unsigned char length[4] = {
      static_cast<unsigned char>(field.size() >> 24), static_cast<unsigned char>(field.size() >> 16),
      static_cast<unsigned char>(field.size() >> 8), static_cast<unsigned char>(field.size())};
  crypto_generichash_update(&state, length, sizeof length);
  crypto_generichash_update(&state, reinterpret_cast<const unsigned char*>(field.data()), field.size());
}

}  // namespace

std::int64_t sender_id(std::string_view machine_id, std::string_view program, std::string_view instance) {
  init_sodium();
  unsigned char hash[crypto_generichash_BYTES];
  crypto_generichash_state state;
  crypto_generichash_init(&state, nullptr, 0, sizeof hash);
  for (const auto field : {std::string_view("cvo-slam sender"), machine_id, program, instance})
    hash_field(state, field);  // length-prefixed: ("ab", "c") is not ("a", "bc")
  crypto_generichash_final(&state, hash, sizeof hash);
  std::uint64_t id = 0;
  for (int i = 0; i < 8; ++i) id = (id << 8) | hash[i];
  return id == 0 ? 1 : static_cast<std::int64_t>(id);
}

std::string service_unit(std::string_view text) {
  std::string unit;
  while (!text.empty()) {  // one line per hierarchy: "0::/system.slice/cvo-trackerd.service"
    const auto newline = text.find('\n');
    std::string_view path = text.substr(0, newline);
    text = newline == std::string_view::npos ? std::string_view{} : text.substr(newline + 1);
    for (std::size_t at = path.rfind('/'); at != std::string_view::npos; at = path.rfind('/')) {
      const auto component = path.substr(at + 1);
      if (component.ends_with(".service")) {
        unit = std::string(component);
        break;
      }
      path = path.substr(0, at);
    }
    if (!unit.empty()) return unit;
  }
  return unit;
}

std::int64_t this_process_sender_id(std::string_view program) {
  init_sodium();
  std::string machine = read_all("/etc/machine-id");
  while (!machine.empty() && (machine.back() == '\n' || machine.back() == ' ')) machine.pop_back();
  // The unit's own process only (systemd >= 248 names it in SYSTEMD_EXEC_PID): processes that a
  // service's process starts (a test runner's daemons) are in its cgroup too, but not the unit.
  const char* exec_pid = std::getenv("SYSTEMD_EXEC_PID");
  const bool unit_process = exec_pid != nullptr && std::atol(exec_pid) == static_cast<long>(getpid());
  std::string instance = unit_process ? service_unit(read_all("/proc/self/cgroup")) : std::string();
  if (instance.empty()) {  // started by hand: a sender of its own
    unsigned char random[8];
    randombytes_buf(random, sizeof random);
    instance.assign("random:").append(reinterpret_cast<const char*>(random), sizeof random);
  }
  return sender_id(machine, program, instance);
}

}  // namespace cvo::auth
