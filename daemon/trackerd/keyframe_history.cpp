#include "daemon/trackerd/keyframe_history.hpp"

#include <algorithm>

namespace cvo::daemon::trackerd {

KeyframeHistory::KeyframeHistory(std::size_t keyframes, std::size_t keyframe_bytes, std::size_t graph_bytes)
    : slots_(keyframes), keyframe_bytes_(keyframe_bytes), graph_bytes_(graph_bytes) {
  for (auto& slot : slots_) {
    slot.keyframe.reserve(keyframe_bytes);
    slot.graph.reserve(graph_bytes);
  }
}

void KeyframeHistory::reserve_keyframe_bytes(std::size_t keyframe_bytes) {
  if (keyframe_bytes <= keyframe_bytes_) return;
  keyframe_bytes_ = keyframe_bytes;
  for (auto& slot : slots_) slot.keyframe.reserve(keyframe_bytes);  // keeps the bytes held
}

void KeyframeHistory::made(std::int64_t session, std::int64_t id) {
  auto [it, inserted] = newest_.try_emplace(session, id);
  if (!inserted) it->second = std::max(it->second, id);
}

void KeyframeHistory::never_sent(std::int64_t session, std::int64_t id) {
  made(session, id);
  gone_.emplace(session, id);
}

std::size_t KeyframeHistory::index_of(std::int64_t session, std::int64_t id) const {
  const auto it = std::find_if(slots_.begin(), slots_.end(),
                               [&](const Slot& s) { return s.used && s.session == session && s.id == id; });
  return static_cast<std::size_t>(it - slots_.begin());
}

bool KeyframeHistory::keep_keyframe(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message) {
  made(session, id);
  if (slots_.empty() || message.size() > keyframe_bytes_) return false;
  auto index = index_of(session, id);  // the same keyframe again (not expected): its own slot
  if (index == slots_.size()) {
    index = next_;
    next_ = (next_ + 1) % slots_.size();
  }
  Slot& slot = slots_[index];
  slot.used = true;
  slot.session = session;
  slot.id = id;
  slot.keyframe.assign(message.begin(), message.end());  // within capacity: no allocation
  slot.graph.clear();
  return true;
}

bool KeyframeHistory::keep_graph(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message) {
  const auto index = index_of(session, id);
  if (index == slots_.size() || message.size() > graph_bytes_) return false;
  slots_[index].graph.assign(message.begin(), message.end());
  return true;
}

std::optional<KeyframeHistory::Held> KeyframeHistory::find(std::int64_t session, std::int64_t id) const {
  const auto index = index_of(session, id);
  if (index == slots_.size()) return std::nullopt;
  return Held{slots_[index].keyframe, slots_[index].graph};
}

KeyframeHistory::Answer KeyframeHistory::answer(std::int64_t session, std::span<const std::int64_t> ids,
                                                const Send& send, const Afford& afford) {
  Answer answer;
  const auto newest = newest_.find(session);
  if (newest == newest_.end()) return answer;
  answer.ours = true;
  std::vector<std::int64_t> wanted(ids.begin(), ids.end());
  std::sort(wanted.begin(), wanted.end());
  wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
  for (const std::int64_t id : wanted) {
    if (id < 0 || id > newest->second) {
      answer.never.push_back(id);
    } else if (const auto held = find(session, id)) {
      if (afford && !afford(held->keyframe.size() + held->graph.size())) {
        answer.over.push_back(id);
        continue;
      }
      send("CVO_KEYFRAME", held->keyframe);  // the keyframe first: the back end refuses a graph without it
      if (!held->graph.empty()) send("CVO_LOCAL_GRAPH", held->graph);
      ++resent_;
      answer.sent.push_back(id);
    } else {
      answer.lost.push_back(id);
      if (gone_.emplace(session, id).second) ++lost_;
    }
  }
  return answer;
}

}  // namespace cvo::daemon::trackerd
