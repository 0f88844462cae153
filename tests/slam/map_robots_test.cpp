// A fleet's map, robot by robot: sessions and keyframes per robot, and the loops between robots
// (not those within one robot's sessions), as the back end's log and cvo-log map report them.
#include "libcvo/slam/map_robots.hpp"

#include <gtest/gtest.h>

#include "tests/support/map_session.hpp"

namespace cvo::slam {
namespace {

MapLoop loop(core::SessionId from, core::SessionId to) {
  MapLoop l;
  l.from_session = from;
  l.to_session = to;
  return l;
}

TEST(MapRobots, CountsEachRobotsSessionsAndTheLoopsBetweenRobots) {
  Map map;
  map.sessions = {test::map_session(1, true, 1, 2, 0, {}), test::map_session(2, true, 1, 1, 3, {}),
                  test::map_session(3, false, 3, 1, -1, {}), test::map_session(4, true, 1, 1, 2, {})};
  map.sessions[0].robot = map.sessions[1].robot = "hall-b";  // one robot, restarted
  map.sessions[2].robot = "dock-1";
  map.sessions[3].robot = "hall-a";
  map.keyframes = {{1, 0, 0, {}}, {1, 1, 1, {}}, {2, 0, 2, {}}, {3, 0, 3, {}}, {4, 0, 4, {}}};
  map.loops = {loop(1, 1), loop(1, 2), loop(2, 4), loop(4, 1), loop(1, 4)};

  const MapRobots robots = map_robots(map);
  ASSERT_EQ(robots.robots.size(), 3u);
  EXPECT_EQ(robots.robots[0].robot, "dock-1");
  EXPECT_EQ(robots.robots[0].placed, 0u);
  EXPECT_EQ(robots.robots[2].robot, "hall-b");
  EXPECT_EQ(robots.robots[2].sessions, 2u);
  EXPECT_EQ(robots.robots[2].keyframes, 3u);
  ASSERT_EQ(robots.loops_between.size(), 1u) << "the loops within hall-b's sessions are not between robots";
  EXPECT_EQ(robots.loops_between[0].first, "hall-a");
  EXPECT_EQ(robots.loops_between[0].second, "hall-b");
  EXPECT_EQ(robots.loops_between[0].loops, 3u);
  EXPECT_EQ(describe(robots),
            "robots: dock-1 (1 session, 0 placed, 1 keyframe), hall-a (1 session, 1 placed, 1 keyframe), hall-b (2 "
            "sessions, 2 placed, 3 keyframes); loops between robots: hall-a-hall-b 3");
}

TEST(MapRobots, ASessionWhoseRobotIsNotKnownIsShownSoAndAnEmptyMapHasNone) {
  EXPECT_EQ(describe(map_robots(Map{})), "robots: none; loops between robots: none");
  Map map;
  map.sessions = {test::map_session(1, true, 1, 0, 0, {})};
  EXPECT_EQ(describe(map_robots(map)),
            "robots: (not named) (1 session, 1 placed, 0 keyframes); loops between robots: none");
}

}  // namespace
}  // namespace cvo::slam
