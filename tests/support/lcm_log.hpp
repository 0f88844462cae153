#pragma once
// What a daemon published, read back from an LCM log (the file:// provider's output or
// lcm-logger's): every message of the cvo-slam channels, decoded with the checking decoder.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>
#include <thread>
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
#include "libcvo/lcm/chunks.hpp"
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
  int keyframe_chunks = 0;  // slices on CVO_KEYFRAME_CHUNK: their messages are in keyframes, local_graphs
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

// A slice: once its message is complete, that message as if it had been logged whole.
inline void add_slice(const ::lcm::LogEvent& e, cvo::lcm::ChunkAssembly& slices, PublishedLog& log) {
  std::string error;
  const auto chunk = cvo::lcm::decode<cvo_lcm::keyframe_chunk_t>(e.data, e.datalen, &error);
  if (!chunk) {
    ++log.undecodable;
    ADD_FAILURE() << e.channel << ": " << error;
    return;
  }
  auto added = slices.add(*chunk);
  if (added.outcome == cvo::lcm::ChunkAssembly::Added::Outcome::kRefused)
    ADD_FAILURE() << e.channel << ": " << added.why;
  if (added.outcome != cvo::lcm::ChunkAssembly::Added::Outcome::kComplete) return;
  ::lcm::LogEvent whole = e;
  whole.data = added.message.data();
  whole.datalen = static_cast<std::int32_t>(added.message.size());
  if (chunk->message == cvo_lcm::keyframe_chunk_t::KEYFRAME)
    add_decoded(whole, log.keyframes, log.undecodable);
  else
    add_decoded(whole, log.local_graphs, log.undecodable);
}

/// Records the channels matching `channels` (an LCM regex) from `url` into an LCM log, as
/// lcm-logger does, in a thread of its own from construction to destruction, but with room for a
/// burst: lcm-logger keeps LCM's default queue of 30 messages per subscription, and on a loaded
/// machine misses some of a keyframe's slices (CVO_KEYFRAME_CHUNK) when it falls behind.
class LcmRecorder {
 public:
  LcmRecorder(const std::string& url, const std::string& channels, const std::filesystem::path& file)
      : lcm_(url), log_(file.string(), "w") {
    lcm_.subscribe(channels, &LcmRecorder::handle, this)->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~LcmRecorder() {
    stop_ = true;
    thread_.join();
  }
  LcmRecorder(const LcmRecorder&) = delete;
  LcmRecorder& operator=(const LcmRecorder&) = delete;
  [[nodiscard]] bool good() { return lcm_.good() && log_.good(); }

 private:
  void handle(const ::lcm::ReceiveBuffer* b, const std::string& channel) {
    ::lcm::LogEvent e{0, b->recv_utime, channel, static_cast<std::int32_t>(b->data_size), b->data};
    log_.writeEvent(&e);
  }
  ::lcm::LCM lcm_;
  ::lcm::LogFile log_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

inline PublishedLog read_published(const std::filesystem::path& file) {
  PublishedLog log;
  ::lcm::LogFile in(file.string(), "r");
  if (!in.good()) {
    ADD_FAILURE() << "cannot read LCM log " << file;
    return log;
  }
  cvo::lcm::ChunkAssembly slices;  // a tracker on a network sends keyframes in slices
  while (const ::lcm::LogEvent* e = in.readNextEvent()) {
    if (e->channel == "CVO_KEYFRAME_CHUNK") {
      ++log.keyframe_chunks;
      add_slice(*e, slices, log);
    } else if (e->channel == "CVO_POSE")
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
