// cvo-map: the map a robot navigates by, from a cvo-backendd keyframe store: the store replayed as
// the daemon replays it at start-up, the final global optimisation, then the occupancy grid, the
// coloured cloud and the OctoMap (libcvo/io/map_files.hpp). The store is only read, so it can run
// while the daemon runs; a damaged record costs only itself (store_map.hpp).
//
// A contract that scripts rely on (extras may be added, nothing here changed):
//   cvo-map STORE --out DIR [--plot PNG] [--config FILE] [--set key=value]... [--vocabulary FILE]
//   writes DIR/grid.pgm, DIR/grid.yaml, DIR/cloud.ply, DIR/octomap.bt; the summary on stdout
//   ("records: ...", "map: ...", "wrote: ..."), each damaged stretch and skipped record on stderr;
//   exit status 0 ok, 1 bad input (the message names the file), 2 usage error.
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/config/config.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/map_files.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/store/replay.hpp"
#include "program/cli.hpp"
#include "program/configuration.hpp"
#include "store_map.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;
using program::UsageError;

constexpr const char* kSynopsis =
    "cvo-map STORE --out DIR [--plot PNG] [--config FILE] [--set key=value]... [--vocabulary FILE]";

constexpr const char* kDescription =
    R"help(Makes the map a robot navigates by from STORE, a cvo-backendd keyframe store (backendd.store),
and writes it into DIR:
  grid.pgm, grid.yaml  the occupancy grid as Nav2's map_server loads it (mode trinary, resolution,
                       origin, thresholds), with map_T_grid, the grid frame's pose in the map frame
  cloud.ply            coloured points in the map frame, voxel-downsampled
  octomap.bt           the 3-D occupancy octree (OctoMap; octovis, convert_octree read it)
The store is replayed as cvo-backendd replays it at start-up: every record decoded once, each
keyframe and local graph once, loops detected and the keyframe graph optimised as the daemon does,
then the final global optimisation, and each keyframe's local map placed at its pose. Only the
sessions placed in the map are mapped.

STORE is only read (never written, renamed or cut), so cvo-map can run while the daemon appends
to it: a record being written is left out. A damaged stretch of the file costs only the records in
it, and a record that cannot be decoded or applied only itself: each is named on stderr with its
offset in the file and why.

stdout, three lines: "records: N intact, S skipped; no damage" (or "; B damaged bytes skipped (D
stretches)"), "map: K keyframes and G local graphs applied, M keyframes in the grid (R refused), P of Q
sessions in the map", "wrote: FILES".)help";

constexpr const char* kNotes =
    R"(configuration: the same keys as cvo-backendd's (loop closure, pose graph, mapping.*: cell size,
voxel size, the obstacle height band, mapping.base_T_camera); give the daemon's --config to get its
map. vocabulary: --vocabulary, else backendd.vocabulary of the configuration ("default": the
committed one of the source tree cvo-map was built from, else the installed share/cvo-slam copy).
No map (an empty store, one no record of which could be used, or keyframes none of which shows which
way is up yet) is bad input (exit 1).)";

struct Arguments {
  fs::path store, out;
  std::optional<fs::path> plot, config, vocabulary;
  std::vector<std::string> sets;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_option("STORE", args.store, "the keyframe store (cvo-backendd's backendd.store)")->required();
  app.add_option("--out", args.out, "the folder the map's four files go to (created if needed)")
      ->required()
      ->type_name("DIR");
  app.add_option("--plot", args.plot, "also draw the grid with the keyframe trajectory on it")->type_name("PNG");
  app.add_option("--config", args.config, "parameters (YAML, see libcvo/config/default.yaml)")->type_name("FILE");
  program::add_set_option(app, args.sets, "mapping.cell_size=0.1");
  app.add_option("--vocabulary", args.vocabulary, "the ORB vocabulary of loop detection (default: see below)")
      ->type_name("FILE");
}

void print_summary(const tools::StoreMap& m, const io::MapFiles& files, const std::optional<fs::path>& plot) {
  std::cout << "records: " << m.records << " intact, " << m.skipped << " skipped; ";
  if (m.damaged_stretches == 0) std::cout << "no damage";
  if (m.damaged_stretches > 0)
    std::cout << m.damaged_bytes << " damaged bytes skipped (" << m.damaged_stretches
              << (m.damaged_stretches == 1 ? " stretch)" : " stretches)");
  if (m.torn_bytes > 0) std::cout << "; a last record cut short (" << m.torn_bytes << " bytes) left out";
  std::cout << "\n";
  const auto statistics = m.mapping.statistics();
  std::cout << "map: " << m.keyframes << " keyframes and " << m.local_graphs << " local graphs applied, "
            << statistics.placed << " keyframes in the grid (" << m.not_mapped.size() << " refused), "
            << m.sessions_placed << " of " << m.sessions << " sessions in the map\n";
  std::cout << "wrote: " << files.grid_pgm.string() << " " << files.grid_yaml.string() << " "
            << files.cloud_ply.string() << " " << files.octomap_bt.string() << (plot ? " " + plot->string() : "")
            << "\n";
}

int run(const Arguments& args) {
  const config::Config config = program::configuration(args.config, args.sets);
  auto vocabulary = loop_closure::Vocabulary::load(
      args.vocabulary ? *args.vocabulary : store::resolve_vocabulary(config.backendd.vocabulary));
  const tools::StoreMap m = tools::map_store(args.store, config, std::move(vocabulary), std::cerr);
  const auto grid = m.mapping.grid();
  if (!grid || m.mapping.statistics().placed == 0) {
    const std::string why = m.keyframes == 0 || m.sessions_placed == 0
                                ? "no keyframe of a session in the map"
                                : "none says which way is up yet (no floor plane seen; mapping.base_T_camera gives the "
                                  "camera's mount)";
    throw io::InputError(args.store, "no map: " + std::to_string(m.records) + " intact records (" +
                                         std::to_string(m.skipped) + " skipped), " + std::to_string(m.keyframes) +
                                         " keyframes applied, " + why);
  }
  const io::MapFiles files = io::write_map_files(args.out, m.mapping);
  if (args.plot) io::write_map_plot(*args.plot, *grid, m.trajectory);
  print_summary(m, files, args.plot);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-map");
  program::describe(app, kSynopsis, kNotes);
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
