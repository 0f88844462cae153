#pragma once
// The store's side of merged keyframes (issue #27 item 3, slam/mapper.hpp: revisits): once the
// mapper merged a keyframe into one covering it, its merge record (merge_record.hpp) is stored
// after the keyframe's own record, which is then garbage (keyframe_store.hpp: discard, compaction),
// so the store grows with the area explored, not with the time spent in it.
//
// Replayed from the store, a merged keyframe is merged again by its own replay, and its merge record
// follows it: that record, once seen, makes the keyframe's record garbage again (garbage is counted
// per run). A merge the replay made whose record never came (a stop between the keyframe and its
// merge) is stored at the end of the replay. Owned by the thread that applies records to the mapper.
#include <cstdint>
#include <map>
#include <optional>
#include <utility>

#include "daemon/backendd/keyframe_store.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::daemon::backendd {

class StoreMerges {
 public:
  explicit StoreMerges(KeyframeStore& store) : store_(store) {}

  /// The newest keyframe the mapper took of its session, and where its record lies (nullopt: not
  /// on disk). A merge is of one of the two newest keyframes of its session (the newest, merged
  /// when it comes; its predecessor, a session's first, when its successor comes), so only those
  /// are remembered.
  void keyframe(core::SessionId session, std::int64_t id, const std::optional<RecordRef>& stored);
  /// The mapper merged keyframe (merge.session, merge.id). Live: its merge is stored and the
  /// keyframe's record discarded (store_merge). Replayed: the merge's record is waited for.
  Appended merged(const slam::KeyframeMerge& merge, bool replayed, bool may_compact);
  /// A merge record replayed from the store: the keyframe it names is garbage.
  void record_replayed(const slam::KeyframeMerge& merge, bool may_compact);
  /// The replay is over: merges it made that have no record yet are stored now.
  void replay_done(bool may_compact);

  /// Compactions this made (the store counts them too).
  [[nodiscard]] std::int64_t compactions() const { return compactions_; }

 private:
  // Appends `merge`, then discards the keyframe's record at `keyframe` (when known) unless the merge
  // could not be kept (Appended::kNotDurable: the keyframe's record must stay).
  Appended store(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& keyframe, bool may_compact);

  KeyframeStore& store_;
  // Each session's two newest keyframes: where their records lie, by id.
  std::map<core::SessionId, std::map<std::int64_t, std::optional<RecordRef>>> newest_;
  // Replayed merged keyframes whose merge record has not come yet: where their record lies.
  std::map<std::pair<core::SessionId, std::int64_t>, std::pair<slam::KeyframeMerge, std::optional<RecordRef>>>
      awaiting_;
  std::int64_t compactions_ = 0;
};

}  // namespace cvo::daemon::backendd
