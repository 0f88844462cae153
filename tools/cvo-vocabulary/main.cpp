// cvo-vocabulary: trains the bag-of-words vocabulary tree of loop closure from the ORB features
// of a set of images, and describes a vocabulary file.
//
// A contract that scripts rely on: the subcommands, their arguments and the exit codes 0 (ok),
// 1 (bad input; the message names the file) and 2 (usage error).
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/loop_closure/orb_features.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "program/cli.hpp"
#include "tools/cvo-vocabulary/image_list.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kDescription =
    "Trains the bag-of-words vocabulary tree of loop closure from the ORB features of a set of images, and\n"
    "describes a vocabulary file.\n";

constexpr const char* kTrainNotes =
    R"(Extracts ORB features from every training image and builds a vocabulary tree on their descriptors
(hierarchical k-medians, Hamming distance, k-means++ seeding; TF-IDF weights from the training
images), written to OUT.voc. Each INPUT is an image file, a TUM-layout folder (its rgb.txt is read)
or a folder of image files. The same images and options always give the same file.)";

constexpr const char* kInfoDescription =
    "Loads FILE.voc, verifies it (format, checksum, tree) and prints what it holds.";

struct Arguments {
  std::string command;
  fs::path file;  // OUT.voc or FILE.voc
  std::vector<fs::path> inputs;
  loop_closure::VocabularyParameters vocabulary;
  core::LoopVerificationParameters orb;  // its orb_* (extract_orb)
  std::size_t every = 1;
};

template <class T>
void add_count(CLI::App& command, const std::string& name, T& value, const std::string& help, T lo, T hi) {
  command.add_option(name, value, help)->transform(program::kDecimal)->check(CLI::Range(lo, hi));
}

void add_train(CLI::App& app, Arguments& args) {
  CLI::App* train = app.add_subcommand("train", "Trains a vocabulary tree on the ORB features of images.");
  program::describe(*train,
                    "cvo-vocabulary train OUT.voc INPUT... [--k K] [--levels L] [--every N] [--features F] [--seed S]",
                    kTrainNotes);
  train->add_option("OUT.voc", args.file, "the vocabulary file to write")->required();
  train->add_option("INPUT", args.inputs, "an image file, a TUM-layout folder or a folder of image files")
      ->required()
      ->default_str("");  // no default to show
  add_count(*train, "--k", args.vocabulary.branching, "branching factor", 2, 256);
  add_count(*train, "--levels", args.vocabulary.levels, "depth of the tree: at most K^L words", 1, 16);
  add_count<std::size_t>(*train, "--every", args.every, "take every N-th image of each folder, from the first", 1,
                         1'000'000);
  add_count(*train, "--features", args.orb.orb_features, "ORB features per image", 1, 1'000'000);
  train->add_option("--seed", args.vocabulary.seed, "seed of the k-means++ seeding, unsigned 64-bit")
      ->transform(program::kDecimal);
}

void add_info(CLI::App& app, Arguments& args) {
  CLI::App* info = app.add_subcommand("info", kInfoDescription);
  program::describe(*info, "cvo-vocabulary info FILE.voc");
  info->add_option("FILE.voc", args.file, "the vocabulary file to verify and describe")->required();
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
  Arguments args;
  CLI::App app(kDescription, "cvo-vocabulary");
  program::describe(app,
                    "cvo-vocabulary train OUT.voc INPUT... [--k K] [--levels L] [--every N] [--features F] [--seed S]\n"
                    "       cvo-vocabulary info FILE.voc");
  add_train(app, args);
  add_info(app, args);
  app.require_subcommand(1);
  return program::cli_main(app, argc, argv, [&] {
    args.command = app.get_subcommands().front()->get_name();
    return run(args);
  });
}
