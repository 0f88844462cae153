// A forger on an open bus cannot delete a tracker's spool (issue 48): the real cvo-trackerd on the
// embedded clip, with a spool and no back end, while the test sends CVO_MAP_CORRECTIONs for the
// tracker's session that say the back end holds keyframes below a million. Before the fix, any such
// word that decoded made the tracker delete every spooled keyframe and exit without naming what was
// not acknowledged; now only a word the tracker applies acknowledges anything, and never beyond the
// newest keyframe it published.
//
// Runs only inside tests/support/in-private-netns (CVO_PRIVATE_NETNS=1).
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;
using cvo::testing::scaled;
using Spooled = std::set<std::pair<std::int64_t, bool>>;  // keyframe id, local graph

constexpr const char* kUrl = cvo::testing::kPrivateLcmUrl;
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
constexpr std::int64_t kAMillion = 1'000'000;

// What the test hears of the tracker: its session, the newest keyframe its poses name, the last
// frame tracked, and its newest CVO_STATUS.
struct Heard {
  std::mutex mutex;
  std::int64_t session = 0, newest_keyframe = -1, last_frame = -1;
  std::optional<cvo_lcm::status_t> newest_status;
  void pose(const ::lcm::ReceiveBuffer* b, const std::string&) {
    const auto p = lcm::decode<cvo_lcm::pose_t>(b->data, static_cast<int>(b->data_size), nullptr);
    if (!p) return;
    const std::lock_guard lock(mutex);
    session = p->session;
    newest_keyframe = std::max(newest_keyframe, p->keyframe_id);
    last_frame = std::max(last_frame, p->frame_index);
  }
  void status_message(const ::lcm::ReceiveBuffer* b, const std::string&) {
    auto s = lcm::decode<cvo_lcm::status_t>(b->data, static_cast<int>(b->data_size), nullptr);
    if (!s || s->process != "cvo-trackerd") return;
    const std::lock_guard lock(mutex);
    newest_status = std::move(*s);
  }
};

// A CVO_MAP_CORRECTION for `session`, unplaced, of revision 1 of a back end started at `epoch`,
// acknowledging keyframes below a million; `finite` false: its correction is not finite.
std::vector<std::uint8_t> forged(std::int64_t session, std::int64_t epoch, bool finite = true) {
  auto m = lcm::to_message(slam::SessionCorrection{1, {session, false, session, 1, -1, {}}, {}}, core::wall_utime(),
                           epoch, kAMillion);
  if (!finite) m.session.correction.position[0] = std::numeric_limits<double>::infinity();
  return lcm::encode(m);
}

class ForgedAcknowledgement : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = cvo::testing::udp_test_skip_reason(); !why.empty()) GTEST_SKIP() << why;
    lcm_.emplace(kUrl);  // only now: inside the private namespace
    ASSERT_TRUE(lcm_->good());
    lcm_->subscribe("CVO_POSE", &Heard::pose, &heard_);
    lcm_->subscribe("CVO_STATUS", &Heard::status_message, &heard_);
  }

  // cvo-trackerd on the clip, spooling, with `linger_s`; it stays up after the clip's last frame.
  void start(double linger_s) {
    trackerd_.emplace(
        fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
        std::vector<std::string>{"--source", "tum:" + kClip.string(), "--lcm-url", kUrl, "--deterministic", "--set",
                                 "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set",
                                 "trackerd.spool=" + spool_.string(), "--set",
                                 "trackerd.linger_s=" + std::to_string(linger_s)},
        err_);
  }

  void handle_for(std::chrono::milliseconds d) {
    for (const auto end = std::chrono::steady_clock::now() + d; std::chrono::steady_clock::now() < end;)
      lcm_->handleTimeout(20);
  }

  // Until the clip's 50 frames are tracked (at most a minute), `each` called every 250 ms meanwhile.
  template <class Each>
  void track_the_clip(Each each) {
    for (int i = 0; i < 240 && last_frame() < 49; ++i) {
      handle_for(250ms);
      each();
    }
    ASSERT_EQ(last_frame(), 49) << cvo::testing::slurp(err_);
    handle_for(500ms);  // the last keyframes' messages are out
  }

  // SIGTERM, and its exit code (-9: none within the time), still hearing its last CVO_STATUS.
  int stop() {
    trackerd_->signal(SIGTERM);
    for (const auto end = std::chrono::steady_clock::now() + scaled(30s); std::chrono::steady_clock::now() < end;) {
      handle_for(100ms);
      if (const auto code = trackerd_->wait_for(0ms)) {
        handle_for(200ms);
        return *code;
      }
    }
    return -9;
  }

  void forge(const std::vector<std::uint8_t>& bytes) {
    lcm_->publish("CVO_MAP_CORRECTION", bytes.data(), static_cast<unsigned>(bytes.size()));
  }

  // The keyframes and local graphs of `session` that the spool holds.
  [[nodiscard]] Spooled spooled(std::int64_t session) const {
    Spooled out;
    const std::string prefix = core::session_name(session).substr(2) + "-";
    for (const auto& file : fs::directory_iterator(spool_)) {
      const std::string name = file.path().filename().string();
      if (!name.starts_with(prefix) || !name.ends_with(".lcm")) continue;
      const auto id = std::stoll(name.substr(prefix.size()));
      out.emplace(id, name.ends_with("-g.lcm"));
    }
    return out;
  }

  std::int64_t last_frame() {
    const std::lock_guard lock(heard_.mutex);
    return heard_.last_frame;
  }
  std::pair<std::int64_t, std::int64_t> session_and_newest() {
    const std::lock_guard lock(heard_.mutex);
    return {heard_.session, heard_.newest_keyframe};
  }
  std::int64_t bad(int kind) {
    const std::lock_guard lock(heard_.mutex);
    return heard_.newest_status ? heard_.newest_status->bad_messages[kind] : -1;
  }

  cvo::test::TempDir dir_;
  const fs::path spool_ = dir_.path() / "spool";
  const fs::path err_ = dir_.path() / "trackerd.txt";
  std::optional<::lcm::LCM> lcm_;
  Heard heard_;
  std::optional<DaemonProcess> trackerd_;
};

// What a forger who wants his word to win sends: an epoch a year ahead (a newer epoch beats every
// back end's), or a correction that is no number. The tracker refuses both, counts them, and
// acknowledges nothing: every keyframe and local graph stays in the spool, and the exit names them
// all as not acknowledged.
TEST_F(ForgedAcknowledgement, WordsTheTrackerRefusesLeaveEveryKeyframeInTheSpool) {
  start(10);
  const std::int64_t in_a_year = core::wall_utime() + 365LL * 86400 * 1'000'000;
  int sent = 0;
  track_the_clip([&] {
    const auto [session, newest] = session_and_newest();
    if (newest < 1) return;  // keyframe 0's graph out first: the session is one the tracker waits for
    forge(forged(session, in_a_year));
    forge(forged(session, core::wall_utime(), false));
    sent += 2;
  });
  ASSERT_GE(sent, 4) << cvo::testing::slurp(err_);
  const auto [session, newest] = session_and_newest();
  EXPECT_EQ(stop(), 0) << cvo::testing::slurp(err_);

  Spooled every;
  for (std::int64_t id = 0; id <= newest; ++id) every.insert({{id, false}, {id, true}});
  EXPECT_EQ(spooled(session), every) << "keyframes 0-" << newest << ", each with its local graph\n"
                                     << cvo::testing::slurp(err_);
  const std::string note = "exit: keyframes 0-" + std::to_string(newest) + " of session " +
                           core::session_name(session) + " not acknowledged";
  EXPECT_NE(cvo::testing::slurp(err_).find(note), std::string::npos) << cvo::testing::slurp(err_);
  EXPECT_EQ(bad(cvo_lcm::status_t::BAD_IMPLAUSIBLE) + bad(cvo_lcm::status_t::BAD_NOT_FINITE), sent)
      << "each forged word refused and counted";
  std::printf("%d forged words acknowledging a million refused; keyframes 0-%lld all in the spool\n", sent,
              static_cast<long long>(newest));
}

// A word the tracker applies (a back end it has never heard, of a present epoch: on an open bus a
// forger can send that too) acknowledges no further than what was published: once the clip is
// tracked, every keyframe but the open one, whose local graph goes out at the stop. That one stays
// in the spool, is waited for through the linger and named at the exit; the claim is counted.
TEST_F(ForgedAcknowledgement, AWordTheTrackerAppliesCoversOnlyWhatWasPublished) {
  start(1);
  track_the_clip([] {});
  const auto [session, newest] = session_and_newest();
  ASSERT_GE(newest, 2) << cvo::testing::slurp(err_);
  forge(forged(session, core::wall_utime()));
  handle_for(scaled(500ms));
  EXPECT_EQ(stop(), 0) << cvo::testing::slurp(err_);

  EXPECT_EQ(spooled(session), (Spooled{{newest, false}, {newest, true}}))
      << "keyframes 0-" << newest - 1 << " acknowledged, " << newest << " not\n"
      << cvo::testing::slurp(err_);
  const std::string log = cvo::testing::slurp(err_);
  const std::string note =
      "exit: keyframes " + std::to_string(newest) + " of session " + core::session_name(session) + " not acknowledged";
  EXPECT_NE(log.find(note), std::string::npos) << log;
  EXPECT_NE(log.find("beyond the newest published"), std::string::npos) << log;
  EXPECT_EQ(bad(cvo_lcm::status_t::BAD_IMPLAUSIBLE), 1) << "the claim beyond what was published";
}

}  // namespace
}  // namespace cvo::daemon
