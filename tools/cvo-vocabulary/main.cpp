// cvo-vocabulary: trains the bag-of-words vocabulary tree of loop closure from the ORB features
// of a set of images, and describes a vocabulary file.
//
// A contract that scripts rely on: the subcommands, their arguments and the exit codes 0 (ok),
// 1 (bad input; the message names the file) and 2 (usage error).
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/loop_closure/orb_features.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "tools/common/cli.hpp"
#include "tools/cvo-vocabulary/image_list.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;
using tools::UsageError;

constexpr std::string_view kUsage =
    R"(usage: cvo-vocabulary train OUT.voc INPUT... [--k K] [--levels L] [--every N] [--features F] [--seed S]
       cvo-vocabulary info FILE.voc

train  Extracts ORB features from every training image and builds a vocabulary tree on their
       descriptors (hierarchical k-medians, Hamming distance, k-means++ seeding; TF-IDF weights
       from the training images), written to OUT.voc. Each INPUT is an image file, a TUM-layout
       folder (its rgb.txt is read) or a folder of image files.
  --k K         branching factor, 2..256 (default 10)
  --levels L    depth of the tree, 1..16 (default 4): at most K^L words
  --every N     take every N-th image of each folder, from the first (default 1)
  --features F  ORB features per image (default 1000)
  --seed S      seed of the k-means++ seeding, unsigned 64-bit (default 0)
               The same images and options always give the same file.
info   Loads FILE.voc, verifies it (format, checksum, tree) and prints what it holds.

  -h, --help    this text

exit status: 0 ok, 1 bad input, 2 usage error
)";

struct Arguments {
  bool help = false;
  std::string command;
  fs::path file;               // OUT.voc or FILE.voc
  std::vector<fs::path> inputs;
  loop_closure::VocabularyParameters vocabulary;
  loop_closure::OrbParameters orb;
  std::size_t every = 1;
};

std::uint64_t parse_count(std::string_view option, std::string_view text, std::uint64_t lo, std::uint64_t hi) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    throw UsageError(std::string(option) + " needs an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                     ", not '" + std::string(text) + "'");
  return v;
}

Arguments parse_arguments(int argc, char** argv) {
  Arguments args;
  std::vector<std::string> positional;
  constexpr auto kMax = std::numeric_limits<std::uint64_t>::max();
  for (int k = 1; k < argc; ++k) {
    const std::string_view arg = argv[k];
    const auto value = [&]() -> std::string_view {
      if (k + 1 >= argc) throw UsageError(std::string(arg) + " needs a value");
      return argv[++k];
    };
    if (arg == "--help" || arg == "-h") {
      args.help = true;
    } else if (arg == "--k") {
      args.vocabulary.branching = static_cast<int>(parse_count(arg, value(), 2, 256));
    } else if (arg == "--levels") {
      args.vocabulary.levels = static_cast<int>(parse_count(arg, value(), 1, 16));
    } else if (arg == "--every") {
      args.every = parse_count(arg, value(), 1, 1'000'000);
    } else if (arg == "--features") {
      args.orb.features = static_cast<int>(parse_count(arg, value(), 1, 1'000'000));
    } else if (arg == "--seed") {
      args.vocabulary.seed = parse_count(arg, value(), 0, kMax);
    } else if (arg.size() > 1 && arg.front() == '-') {
      throw UsageError("unknown option '" + std::string(arg) + "'");
    } else {
      positional.emplace_back(arg);
    }
  }
  if (args.help) return args;
  if (positional.empty()) throw UsageError("expected a command: train or info");
  args.command = positional[0];
  if (args.command == "train") {
    if (positional.size() < 3) throw UsageError("train needs OUT.voc and at least one INPUT");
    args.file = positional[1];
    args.inputs.assign(positional.begin() + 2, positional.end());
  } else if (args.command == "info") {
    if (positional.size() != 2) throw UsageError("info needs exactly one FILE.voc");
    args.file = positional[1];
  } else {
    throw UsageError("unknown command '" + args.command + "' (train or info)");
  }
  return args;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string hex(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

int train(const Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<fs::path> images = tools::list_images(args.inputs, args.every);
  std::vector<cv::Mat> descriptors;
  std::size_t total = 0;
  const bool progress = ::isatty(STDERR_FILENO) != 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const cv::Mat bgr = cv::imread(images[i].string(), cv::IMREAD_COLOR);
    if (bgr.empty()) throw io::InputError(images[i], "cannot read as an image");
    descriptors.push_back(loop_closure::extract_orb(bgr, args.orb).descriptors);
    total += static_cast<std::size_t>(descriptors.back().rows);
    if (progress) std::cerr << "\rcvo-vocabulary: features of image " << i + 1 << " / " << images.size() << std::flush;
  }
  if (progress) std::cerr << "\n";
  if (total == 0) throw io::InputError(args.inputs.front(), "no ORB features in any training image");
  const double feature_s = seconds_since(start);
  const auto vocabulary = loop_closure::Vocabulary::train(descriptors, args.vocabulary);
  const double cluster_s = seconds_since(start) - feature_s;
  vocabulary.save(args.file);
  std::printf("images          %zu\ndescriptors     %zu\n", images.size(), total);
  std::printf("vocabulary      k %d, L %d, %zu words, %zu nodes, seed %llu\n", vocabulary.branching(),
              vocabulary.levels(), vocabulary.words(), vocabulary.nodes().size(),
              static_cast<unsigned long long>(args.vocabulary.seed));
  std::printf("file            %s (%ju bytes, checksum %s)\n", args.file.c_str(), fs::file_size(args.file),
              hex(vocabulary.checksum()).c_str());
  std::printf("time            %.1f s (features %.1f s, clustering %.1f s)\n", seconds_since(start), feature_s,
              cluster_s);
  return 0;
}

int info(const Arguments& args) {
  const auto vocabulary = loop_closure::Vocabulary::load(args.file);  // verifies, or throws InputError
  std::printf("file             %s\n", args.file.c_str());
  std::printf("format version   %u\n", unsigned{loop_closure::Vocabulary::kFormatVersion});
  std::printf("branching k      %d\n", vocabulary.branching());
  std::printf("depth L          %d\n", vocabulary.levels());
  std::printf("words            %zu\n", vocabulary.words());
  std::printf("nodes            %zu\n", vocabulary.nodes().size());
  std::printf("training images  %zu\n", vocabulary.training_images());
  std::printf("checksum         %s OK\n", hex(vocabulary.checksum()).c_str());
  return 0;
}

int run(const Arguments& args) { return args.command == "train" ? train(args) : info(args); }

}  // namespace

int main(int argc, char** argv) {
  return tools::cli_main("cvo-vocabulary", kUsage, argc, argv, parse_arguments, run);
}
