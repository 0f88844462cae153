#include "daemon/backendd/store_merges.hpp"

#include "daemon/backendd/merge_record.hpp"

namespace cvo::daemon::backendd {

Appended StoreMerges::store(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& keyframe,
                            bool may_compact) {
  const Appended appended = store_.append(RecordKind::kMerge, encode_merge(merge));
  if (appended == Appended::kNotDurable) return appended;  // held records are written before any newer one
  if (keyframe && store_.discard(*keyframe, may_compact)) ++compactions_;
  return appended;
}

void StoreMerges::keyframe(core::SessionId session, std::int64_t id, const std::optional<RecordRef>& stored) {
  auto& newest = newest_[session];
  newest.insert_or_assign(id, stored);
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

void StoreMerges::record_replayed(const slam::KeyframeMerge& merge, bool may_compact) {
  const auto it = awaiting_.find({merge.session, merge.id});
  if (it == awaiting_.end()) return;  // its keyframe's record was compacted away before
  if (const auto& keyframe = it->second.second; keyframe && store_.discard(*keyframe, may_compact)) ++compactions_;
  awaiting_.erase(it);
}

void StoreMerges::replay_done(bool may_compact) {
  for (const auto& [key, merge] : awaiting_) store(merge.first, merge.second, may_compact);
  awaiting_.clear();
}

}  // namespace cvo::daemon::backendd
