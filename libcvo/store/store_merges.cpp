#include "libcvo/store/store_merges.hpp"

#include <algorithm>

#include "libcvo/store/merge_record.hpp"

namespace cvo::store {

void StoreMerges::discard(const RecordRef& where, bool may_compact) {
  if (!store_.discard(where, may_compact)) return;
  ++compactions_;
  follow_compaction();
}

void StoreMerges::follow_compaction() {
  const auto follow = [&](auto& refs) {
    for (auto it = refs.begin(); it != refs.end();) {
      const auto now = store_.relocated(it->second);
      if (!now) {
        it = refs.erase(it);
        continue;
      }
      (it++)->second = *now;
    }
  };
  follow(merge_records_);
  follow(graph_records_);
  follow(settled_records_);
  follow(tally_records_);
  for (auto& [session, newest] : newest_)
    for (auto& [id, ref] : newest)
      if (ref) ref = store_.relocated(*ref);
  for (auto& [key, waiting] : awaiting_)
    if (waiting.second) waiting.second = store_.relocated(*waiting.second);
}

Appended StoreMerges::store(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& keyframe,
                            bool may_compact) {
  RecordRef where;
  const Appended appended = store_.append(RecordKind::kMerge, encode_merge(merge), &where);
  if (appended == Appended::kNotDurable) return appended;  // held records are written before any newer one
  if (appended == Appended::kStored) merge_records_.insert_or_assign({merge.session, merge.id}, where);
  if (keyframe) discard(*keyframe, may_compact);
  return appended;
}

void StoreMerges::keyframe(core::SessionId session, std::int64_t id, const std::optional<RecordRef>& stored) {
  auto& newest = newest_[session];
  newest.insert_or_assign(id, stored ? store_.relocated(*stored) : std::nullopt);
  while (newest.size() > 2) newest.erase(newest.begin());
}

Appended StoreMerges::merged(const slam::KeyframeMerge& merge, bool replayed, bool may_compact) {
  std::optional<RecordRef> keyframe;
  if (const auto it = newest_.find(merge.session); it != newest_.end())
    if (const auto k = it->second.find(merge.id); k != it->second.end()) keyframe = k->second;
  if (!replayed) return store(merge, keyframe, may_compact);
  awaiting_.insert_or_assign({merge.session, merge.id}, std::pair{merge, keyframe});
  return Appended::kStored;
}

void StoreMerges::record_replayed(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& stored,
                                  bool may_compact) {
  if (stored)
    if (const auto now = store_.relocated(*stored)) merge_records_.insert_or_assign({merge.session, merge.id}, *now);
  const auto it = awaiting_.find({merge.session, merge.id});
  if (it == awaiting_.end()) return;  // its keyframe's record was compacted away before
  const auto keyframe = it->second.second;
  awaiting_.erase(it);
  if (keyframe) discard(*keyframe, may_compact);
}

void StoreMerges::replay_done(bool may_compact) {
  const auto waiting = std::exchange(awaiting_, {});
  for (const auto& [key, merge] : waiting) store(merge.first, merge.second, may_compact);
}

void StoreMerges::local_graph(core::SessionId session, std::int64_t id, const std::optional<RecordRef>& stored,
                              bool merged) {
  if (!merged || !stored) return;
  if (const auto now = store_.relocated(*stored)) graph_records_.insert_or_assign({session, id}, *now);
}

StoreMerges::EdgeKey StoreMerges::key_of(const slam::SettledEdge& e) {
  const Key a{e.from_session, e.from_id}, b{e.to_session, e.to_id};
  return {std::min(a, b), std::max(a, b), e.robust};
}

void StoreMerges::settled(const slam::Settlement& settlement, bool may_compact) {
  std::vector<RecordRef> garbage;
  // Each stored, replacing its key's record; false: one could not be kept (nothing is discarded
  // then: the records replay to this settlement). Held ones are written in order later; the record
  // they replace stays too.
  const auto store_each = [&](const auto& values, RecordKind kind, auto encode, auto& refs, auto key) {
    for (const auto& value : values) {
      RecordRef where;
      const Appended appended = store_.append(kind, encode(value), &where);
      if (appended == Appended::kNotDurable) return false;
      if (appended != Appended::kStored) continue;
      const auto [it, added] = refs.try_emplace(key(value), where);
      if (!added) garbage.push_back(std::exchange(it->second, where));
    }
    return true;
  };
  if (!store_each(settlement.edges, RecordKind::kSettled, encode_settled, settled_records_, key_of) ||
      !store_each(settlement.tallies, RecordKind::kTally, encode_tally, tally_records_,
                  [](const slam::SessionTally& t) { return t.session; }))
    return;
  const auto take = [&](std::map<Key, RecordRef>& refs, const Key& key) {
    if (const auto it = refs.find(key); it != refs.end()) {
      garbage.push_back(it->second);
      refs.erase(it);
    }
  };
  for (const auto& key : settlement.graphs) take(graph_records_, key);
  for (const auto& key : settlement.keyframes) take(merge_records_, key);
  for (const auto& ref : garbage)
    if (const auto now = store_.relocated(ref)) discard(*now, may_compact);
}

// The record of `key` replayed at `stored`: remembered; one before it for the same key (a stop
// came between the two writes) is garbage.
template <class Refs, class RefKey>
void StoreMerges::replayed(Refs& refs, const RefKey& key, const std::optional<RecordRef>& stored, bool may_compact) {
  const auto now = stored ? store_.relocated(*stored) : std::nullopt;
  if (!now) return;
  const auto [it, added] = refs.try_emplace(key, *now);
  if (added) return;
  const RecordRef older = std::exchange(it->second, *now);
  if (const auto old = store_.relocated(older)) discard(*old, may_compact);
}

void StoreMerges::settled_replayed(const slam::SettledEdge& edge, const std::optional<RecordRef>& stored,
                                   bool may_compact) {
  replayed(settled_records_, key_of(edge), stored, may_compact);
}

void StoreMerges::tally_replayed(const slam::SessionTally& tally, const std::optional<RecordRef>& stored,
                                 bool may_compact) {
  replayed(tally_records_, tally.session, stored, may_compact);
}

}  // namespace cvo::store
