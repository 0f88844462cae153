#pragma once
// The store's side of merged keyframes and settled revisits (slam/mapper.hpp: revisits): a merge's
// or a settlement's records stored, and the records they make garbage discarded, live and when the
// store is replayed (README.md: "Merges and settled revisits"). Owned by the thread that applies
// records to the mapper.
#include <cstdint>
#include <map>
#include <optional>
#include <tuple>
#include <utility>

#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/keyframe_store.hpp"

namespace cvo::store {

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
  /// A merge record replayed from the store, at `stored`: the keyframe it names is garbage.
  void record_replayed(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& stored, bool may_compact);
  /// The replay is over: merges it made that have no record yet are stored now.
  void replay_done(bool may_compact);

  /// The mapper took the local graph of keyframe (session, id), stored at `stored`: remembered when
  /// the keyframe is merged (it may settle).
  void local_graph(core::SessionId session, std::int64_t id, const std::optional<RecordRef>& stored, bool merged);
  /// What slam::Mapper::settle did: its settled edges are stored, each replacing the record of its
  /// pair, then the records it made garbage are discarded (none when a settled edge could not be
  /// kept: the records replay to the same settlement).
  void settled(const slam::Settlement& settlement, bool may_compact);
  /// A settled record replayed from the store, at `stored`.
  void settled_replayed(const slam::SettledEdge& edge, const std::optional<RecordRef>& stored, bool may_compact);
  /// A tally record replayed from the store, at `stored`.
  void tally_replayed(const slam::SessionTally& tally, const std::optional<RecordRef>& stored, bool may_compact);

  /// Compactions this made (the store counts them too).
  [[nodiscard]] std::int64_t compactions() const { return compactions_; }

 private:
  using Key = std::pair<core::SessionId, std::int64_t>;
  using EdgeKey = std::tuple<Key, Key, bool>;
  static EdgeKey key_of(const slam::SettledEdge& edge);
  // Appends `merge`, then discards the keyframe's record at `keyframe` (when known) unless the merge
  // could not be kept (Appended::kNotDurable: the keyframe's record must stay).
  Appended store(const slam::KeyframeMerge& merge, const std::optional<RecordRef>& keyframe, bool may_compact);
  void discard(const RecordRef& where, bool may_compact);
  void follow_compaction();  // every reference held, as the store is now
  template <class Refs, class RefKey>
  void replayed(Refs& refs, const RefKey& key, const std::optional<RecordRef>& stored, bool may_compact);

  KeyframeStore& store_;
  // Each session's two newest keyframes: where their records lie, by id.
  std::map<core::SessionId, std::map<std::int64_t, std::optional<RecordRef>>> newest_;
  // Replayed merged keyframes whose merge record has not come yet: where their record lies.
  std::map<Key, std::pair<slam::KeyframeMerge, std::optional<RecordRef>>> awaiting_;
  std::map<Key, RecordRef> merge_records_, graph_records_;  // of merged keyframes not forgotten yet
  std::map<EdgeKey, RecordRef> settled_records_;
  std::map<core::SessionId, RecordRef> tally_records_;
  std::int64_t compactions_ = 0;
};

}  // namespace cvo::store
