#pragma once
// What a map of several robots says of them: each robot's sessions and keyframes, and the loops
// between robots. A robot is what its tracker names in every message (trackerd.robot, the host's
// name by default); a session belongs to one robot, a robot has a session per tracker start. A loop
// between two sessions of different robots is where one robot's map met another's: a fleet's map is
// one map only where such loops join it.
#include <cstddef>
#include <string>
#include <vector>

#include "libcvo/slam/mapper.hpp"

namespace cvo::slam {

struct RobotInMap {
  std::string robot;  // "" for sessions whose robot is not known (no keyframe of theirs came)
  std::size_t sessions = 0, placed = 0, keyframes = 0;
};

/// Loops between two robots' sessions, the robots in name order (first < second).
struct LoopsBetweenRobots {
  std::string first, second;
  std::size_t loops = 0;
};

struct MapRobots {
  std::vector<RobotInMap> robots;                 // by name
  std::vector<LoopsBetweenRobots> loops_between;  // by the pair's names; pairs with loops only
};

MapRobots map_robots(const Map& map);

/// One line for logs: "robots: hall-a (2 sessions, 2 placed, 40 keyframes), hall-b (...); loops
/// between robots: hall-a-hall-b 5" ("none" when no two robots' sessions share a loop).
std::string describe(const MapRobots& robots);

}  // namespace cvo::slam
