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

bool KeyframeHistory::keep_keyframe(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message,
                                    std::uint32_t crc) {
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
  slot.keyframe_crc = crc;
  slot.graph.clear();
  return true;
}

bool KeyframeHistory::keep_graph(std::int64_t session, std::int64_t id, std::span<const std::uint8_t> message,
                                 std::uint32_t crc) {
  const auto index = index_of(session, id);
  if (index == slots_.size() || message.size() > graph_bytes_) return false;
  slots_[index].graph.assign(message.begin(), message.end());
  slots_[index].graph_crc = crc;
  return true;
}

std::optional<KeyframeHistory::Held> KeyframeHistory::find(std::int64_t session, std::int64_t id) const {
  const auto index = index_of(session, id);
  if (index == slots_.size()) return std::nullopt;
  const Slot& slot = slots_[index];
  return Held{{slot.keyframe, slot.keyframe_crc}, {slot.graph, slot.graph_crc}};
}

std::optional<KeyframeHistory::Held> KeyframeHistory::held_or_noted(std::int64_t session, std::int64_t newest,
                                                                    std::int64_t id, Answer& answer) {
  if (id < 0 || id > newest) {
    answer.never.push_back(id);
    return std::nullopt;
  }
  if (auto held = find(session, id)) return held;
  answer.lost.push_back(id);
  if (gone_.emplace(session, id).second) ++lost_;
  return std::nullopt;
}

KeyframeHistory::Answer KeyframeHistory::answer(std::int64_t session, std::span<const std::int64_t> ids,
                                                std::span<const Wanted> ranges, const Send& send,
                                                const Afford& afford) {
  Answer answer;
  const auto newest = newest_.find(session);
  if (newest == newest_.end()) return answer;
  answer.ours = true;
  const auto sorted_unique = [](std::vector<std::int64_t> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
  };
  const auto sent_once = [&](std::int64_t id) {
    if (std::find(answer.sent.begin(), answer.sent.end(), id) != answer.sent.end()) return;
    ++resent_;
    answer.sent.push_back(id);
  };
  for (const std::int64_t id : sorted_unique({ids.begin(), ids.end()})) {
    const auto held = held_or_noted(session, newest->second, id, answer);
    if (!held) continue;
    if (afford && !afford(held->keyframe.bytes.size() + held->graph.bytes.size())) {
      answer.over.push_back(id);
      continue;
    }
    send({id, false, held->keyframe, std::nullopt});  // the keyframe first: the back end refuses a graph without it
    if (!held->graph.bytes.empty()) send({id, true, held->graph, std::nullopt});
    sent_once(id);
  }
  for (const Wanted& w : ranges) {
    if (std::find(ids.begin(), ids.end(), w.id) != ids.end()) continue;  // sent whole above
    const auto held = held_or_noted(session, newest->second, w.id, answer);
    if (!held) continue;
    const Message& message = w.graph ? held->graph : held->keyframe;
    const lcm::SliceRange slices = lcm::clamp(w.slices, message.bytes.size());
    if (slices.count == 0) continue;  // a graph not published yet, or slices it does not have
    const auto bytes = std::min<std::size_t>(
        message.bytes.size(), static_cast<std::size_t>(slices.count) * cvo_lcm::keyframe_chunk_t::MAX_DATA);
    if (afford && !afford(bytes)) {
      answer.over.push_back(w.id);
      continue;
    }
    send({w.id, w.graph, message, slices});
    sent_once(w.id);
  }
  answer.lost = sorted_unique(std::move(answer.lost));
  answer.never = sorted_unique(std::move(answer.never));
  answer.over = sorted_unique(std::move(answer.over));
  return answer;
}

}  // namespace cvo::daemon::trackerd
