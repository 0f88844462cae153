#pragma once
// What a daemon published, read back from an LCM log (the file:// provider's output or
// lcm-logger's): every message of the cvo-slam channels, decoded with the checking decoder.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/grid_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/lcm/decode.hpp"

namespace cvo::testing {

struct PublishedLog {
  std::vector<cvo_lcm::pose_t> poses;
  std::vector<cvo_lcm::keyframe_t> keyframes;
  std::vector<cvo_lcm::local_graph_t> local_graphs;
  std::vector<cvo_lcm::status_t> statuses;
  std::vector<cvo_lcm::map_t> maps;
  std::vector<cvo_lcm::map_correction_t> map_corrections;
  std::vector<cvo_lcm::grid_t> grids;
  int undecodable = 0;
};

template <class T>
void add_decoded(const ::lcm::LogEvent& e, std::vector<T>& out, int& undecodable) {
  std::string error;
  if (auto m = cvo::lcm::decode<T>(e.data, e.datalen, &error))
    out.push_back(std::move(*m));
  else {
    ++undecodable;
    ADD_FAILURE() << e.channel << ": " << error;
  }
}

/// Appends one event to an LCM log as lcm-logger would (at `utime`); LogFile::writeEvent's result
/// (0: written).
inline int write_event(::lcm::LogFile& log, const std::string& channel, const std::vector<std::uint8_t>& bytes,
                       std::int64_t utime) {
  ::lcm::LogEvent e{};
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<std::int32_t>(bytes.size());
  e.data = const_cast<std::uint8_t*>(bytes.data());
  return log.writeEvent(&e);
}

inline PublishedLog read_published(const std::filesystem::path& file) {
  PublishedLog log;
  ::lcm::LogFile in(file.string(), "r");
  if (!in.good()) {
    ADD_FAILURE() << "cannot read LCM log " << file;
    return log;
  }
  while (const ::lcm::LogEvent* e = in.readNextEvent()) {
    if (e->channel == "CVO_POSE")
      add_decoded(*e, log.poses, log.undecodable);
    else if (e->channel == "CVO_KEYFRAME")
      add_decoded(*e, log.keyframes, log.undecodable);
    else if (e->channel == "CVO_LOCAL_GRAPH")
      add_decoded(*e, log.local_graphs, log.undecodable);
    else if (e->channel == "CVO_STATUS")
      add_decoded(*e, log.statuses, log.undecodable);
    else if (e->channel == "CVO_MAP")
      add_decoded(*e, log.maps, log.undecodable);
    else if (e->channel == "CVO_MAP_CORRECTION")
      add_decoded(*e, log.map_corrections, log.undecodable);
    else if (e->channel == "CVO_GRID")
      add_decoded(*e, log.grids, log.undecodable);
  }
  return log;
}

}  // namespace cvo::testing
