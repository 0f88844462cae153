// cvo-keygen: makes the deployment key file every daemon of one deployment reads (auth.key_file),
// and steps it through a rotation that never stops the fleet (libcvo/auth/key.hpp):
//   cvo-keygen FILE           {}     -> {A}     a new file, mode 0600; an existing one is never overwritten
//   cvo-keygen --add FILE     {A}    -> {A, B}  a new key, accepted; A still signs
//   cvo-keygen --rotate FILE  {A, B} -> {B, A}  the accepted key signs, the other is accepted
//                             {A}    -> {B, A}  a new key signs at once (for a fleet that is stopped)
//   cvo-keygen --retire FILE  {B, A} -> {B}     the key that does not sign is dropped
// Each step is rolled out to every daemon before the next (systemd/README.md). It prints key ids,
// never keys.
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "libcvo/auth/key.hpp"
#include "program/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kSynopsis = "cvo-keygen FILE | --add FILE | --rotate FILE | --retire FILE";

constexpr const char* kDescription =
    R"(Writes the deployment key file of cvo-slam's authenticated bus (auth.key_file): one or two 32-byte
keys, the first signs every message, each one verifies. Without an option it writes a new file,
mode 0600, and refuses to overwrite one that exists. --add, --rotate and --retire change an
existing file in place (written beside it, then renamed over it) for a rotation without stopping
the fleet: roll each step out to every daemon before the next.)";

constexpr const char* kNotes =
    R"(Rotation: --add (A signs, B accepted), then --rotate (B signs, A accepted), then --retire (B
alone). Daemons of neighbouring steps accept each other's messages. systemd/README.md says how the
file is installed (LoadCredential=) and rolled out.)";

struct Arguments {
  fs::path file;
  bool add = false, rotate = false, retire = false;
};

std::string describe(const auth::KeyRing& keys) {
  std::string text = "key " + auth::key_name(keys.signing().id()) + " signs";
  if (keys.keys().size() > 1) text += ", key " + auth::key_name(keys.keys()[1].id()) + " is accepted";
  return text;
}

auth::KeyRing changed(auth::KeyRing ring, const Arguments& args) {
  std::vector<auth::Key> keys = ring.release();
  if (args.add) {
    if (keys.size() == auth::KeyRing::kMaxKeys)
      throw auth::KeyFileError(args.file, "holds two keys already: --retire the one that does not sign first");
    keys.push_back(auth::Key::generate());
  } else if (args.rotate) {
    if (keys.size() == 1)
      keys.insert(keys.begin(), auth::Key::generate());
    else
      std::swap(keys[0], keys[1]);
  } else if (keys.size() == 1) {
    throw auth::KeyFileError(args.file, "holds one key: nothing to retire (a deployment needs a key)");
  } else {
    keys.pop_back();
  }
  return auth::KeyRing(std::move(keys));
}

int run(const Arguments& args) {
  if (static_cast<int>(args.add) + static_cast<int>(args.rotate) + static_cast<int>(args.retire) > 1)
    throw program::UsageError("--add, --rotate and --retire: one at a time");
  if (!args.add && !args.rotate && !args.retire) {
    std::vector<auth::Key> keys;
    keys.push_back(auth::Key::generate());
    const auth::KeyRing ring(std::move(keys));
    auth::create_key_file(args.file, ring);
    std::cout << "cvo-keygen: wrote " << args.file.string() << " (mode 0600): " << describe(ring) << "\n";
    return 0;
  }
  const auth::KeyRing ring = changed(auth::read_key_file(args.file), args);
  auth::replace_key_file(args.file, ring);
  std::cout << "cvo-keygen: "
            << (args.add      ? "added a key to "
                : args.rotate ? "rotated "
                              : "retired a key of ")
            << args.file.string() << ": " << describe(ring) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-keygen");
  program::describe(app, kSynopsis, kNotes);
  app.add_option("FILE", args.file, "the key file")->required();
  app.add_flag("--add", args.add, "add a new key, accepted but not signing yet: {A} -> {A, B}");
  app.add_flag("--rotate", args.rotate, "the accepted key signs: {A, B} -> {B, A} ({A} -> {new, A})");
  app.add_flag("--retire", args.retire, "drop the key that does not sign: {B, A} -> {B}");
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
