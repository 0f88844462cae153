#include "libcvo/slam/map_robots.hpp"

#include <map>
#include <utility>

namespace cvo::slam {
namespace {

std::string shown(const std::string& robot) { return robot.empty() ? "(not named)" : robot; }

}  // namespace

MapRobots map_robots(const Map& map) {
  std::map<std::string, RobotInMap> robots;
  std::map<core::SessionId, std::string> robot_of;
  for (const auto& s : map.sessions) {
    robot_of[s.session] = s.robot;
    RobotInMap& r = robots[s.robot];
    r.robot = s.robot;
    ++r.sessions;
    r.placed += s.placed ? 1 : 0;
  }
  for (const auto& k : map.keyframes)
    if (const auto it = robot_of.find(k.session); it != robot_of.end()) ++robots[it->second].keyframes;
  std::map<std::pair<std::string, std::string>, std::size_t> between;
  for (const auto& l : map.loops) {
    const auto from = robot_of.find(l.from_session), to = robot_of.find(l.to_session);
    if (from == robot_of.end() || to == robot_of.end() || from->second == to->second) continue;
    ++between[std::minmax(from->second, to->second)];
  }
  MapRobots out;
  for (auto& [name, r] : robots) out.robots.push_back(std::move(r));
  for (const auto& [pair, loops] : between) out.loops_between.push_back({pair.first, pair.second, loops});
  return out;
}

std::string describe(const MapRobots& robots) {
  const auto count = [](std::size_t n, const char* what) {
    return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  std::string text = "robots:";
  for (std::size_t i = 0; i < robots.robots.size(); ++i) {
    const auto& r = robots.robots[i];
    text += std::string(i == 0 ? " " : ", ") + shown(r.robot) + " (" + count(r.sessions, "session") + ", " +
            std::to_string(r.placed) + " placed, " + count(r.keyframes, "keyframe") + ")";
  }
  if (robots.robots.empty()) text += " none";
  text += "; loops between robots:";
  for (std::size_t i = 0; i < robots.loops_between.size(); ++i) {
    const auto& b = robots.loops_between[i];
    text += std::string(i == 0 ? " " : ", ") + shown(b.first) + "-" + shown(b.second) + " " + std::to_string(b.loops);
  }
  if (robots.loops_between.empty()) text += " none";
  return text;
}

}  // namespace cvo::slam
