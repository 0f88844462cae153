#include "daemon/trackerd/delivery.hpp"

#include <algorithm>
#include <exception>
#include <map>

#include "libcvo/core/session.hpp"

namespace cvo::daemon::trackerd {
namespace {

// "3, 5-9" of ascending ids.
std::string ranges(const std::vector<std::int64_t>& ids) {
  std::string out;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t j = i;
    while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
    if (!out.empty()) out += ", ";
    out += std::to_string(ids[i]);
    if (j > i) out.append("-").append(std::to_string(ids[j]));
    i = j + 1;
  }
  return out;
}

}  // namespace

Delivery::Delivery(const std::string& spool_dir, std::uintmax_t spool_bytes, double linger_s, std::string* warning)
    : linger_(linger_s) {
  if (spool_dir.empty() || spool_dir == "none") return;
  try {
    spool_.emplace(spool_dir, spool_bytes);
  } catch (const std::exception& e) {
    if (warning != nullptr) *warning = std::string(e.what()) + ": running without a spool";
  }
}

void Delivery::published(std::int64_t session, std::int64_t id, bool graph, std::span<const std::uint8_t> message,
                         Clock::time_point now) {
  if (spool_)
    if (auto why = spool_->keep({session, id, graph, 0}, message); !why.empty()) failures_.push_back(std::move(why));
  if (graph) acks_.ready(session, id, now);  // the back end acknowledges a keyframe with its graph
}

std::optional<std::int64_t> Delivery::acknowledged(std::int64_t session, std::int64_t prefix, Clock::time_point now) {
  const auto newest = newest_published(session);
  if (!newest) return std::nullopt;
  // A word that claims more than went out is no back end's (a forger's, or a fault): it must not
  // delete from the spool, nor count as held, keyframes made after it.
  const std::int64_t taken = std::min(prefix, *newest + 1);
  acks_.acknowledged(session, taken, now);
  ever_acknowledged_ = true;
  const bool lone = lone_.contains({session, taken});  // handed over without its graph, all before it held
  if (spool_) spool_->acknowledged(session, lone ? taken + 1 : taken);
  return taken;
}

std::optional<std::int64_t> Delivery::newest_published(std::int64_t session) const {
  auto newest = acks_.newest(session);
  for (auto it = lone_.lower_bound({session, 0}); it != lone_.end() && it->first == session; ++it)
    newest = std::max(newest.value_or(it->second), it->second);
  return newest;
}

std::vector<std::pair<std::int64_t, std::int64_t>> Delivery::due(Clock::time_point now) {
  std::vector<std::pair<std::int64_t, std::int64_t>> out;
  for (const auto session : acks_.sessions())
    for (const auto id : acks_.due(session, now, 2)) out.emplace_back(session, id);
  return out;
}

std::vector<Spool::Entry> Delivery::left_over(std::int64_t session) const {
  std::vector<Spool::Entry> out;
  if (spool_)
    for (const auto& e : spool_->entries())
      if (e.session != session) out.push_back(e);
  return out;
}

std::optional<std::vector<std::uint8_t>> Delivery::spooled(std::int64_t session, std::int64_t id, bool graph) const {
  if (!spool_) return std::nullopt;
  return spool_->read({session, id, graph, 0});
}

bool Delivery::spool(const Spool::Entry& entry, std::span<const std::uint8_t> message) {
  if (!spool_) return false;
  auto why = spool_->keep(entry, message);
  if (why.empty()) return true;
  failures_.push_back(std::move(why));
  return false;
}

// A keyframe handed over with its graph waits for acknowledgement; one without (the killed session's
// newest, whose graph never went out) cannot be acknowledged: it goes from the spool once all before
// it are (acknowledged()).
void Delivery::handed_over(const std::vector<Spool::Entry>& entries, Clock::time_point now) {
  std::set<std::pair<std::int64_t, std::int64_t>> graphs;
  for (const auto& e : entries)
    if (e.graph) graphs.emplace(e.session, e.id);
  for (const auto& e : entries) {
    if (e.graph) continue;
    if (graphs.contains({e.session, e.id}))
      acks_.ready(e.session, e.id, now);
    else
      lone_.emplace(e.session, e.id);
  }
}

bool Delivery::may_exit(Clock::time_point done_at, Clock::time_point now) const {
  if (!ever_acknowledged_ || now - done_at >= linger_) return true;
  const auto sessions = acks_.sessions();
  return std::all_of(sessions.begin(), sessions.end(), [&](std::int64_t s) { return acks_.unacknowledged(s).empty(); });
}

std::string Delivery::unacknowledged_note() const {
  std::string out;
  for (const auto session : acks_.sessions()) {
    const auto ids = acks_.unacknowledged(session);
    if (ids.empty()) continue;
    out += (out.empty() ? "" : "; ") + std::string("keyframes ") + ranges(ids) + " of session " +
           core::session_name(session);
  }
  if (out.empty()) return out;
  return out + " not acknowledged by the back end" +
         (spool_ ? " (kept in the spool for the next start)" : " (no trackerd.spool: lost if the back end lacks them)");
}

std::string Delivery::spool_note() {
  std::string out;
  if (!failures_.empty()) out = std::to_string(failures_.size()) + " messages not spooled: " + failures_.back();
  failures_.clear();
  if (!spool_) return out;
  std::map<std::int64_t, std::vector<std::int64_t>> dropped;
  for (const auto& e : spool_->dropped())
    if (!e.graph) dropped[e.session].push_back(e.id);
  for (auto& [session, ids] : dropped) {
    std::sort(ids.begin(), ids.end());
    out += (out.empty() ? "" : "; ") + std::string("spool full (trackerd.spool_bytes): dropped keyframes ") +
           ranges(ids) + " of session " + core::session_name(session);
  }
  return out;
}

}  // namespace cvo::daemon::trackerd
