// Ros2Bridge in a build without Cyclone DDS (cyclonedds-dev not found at configure time): the
// daemon links it all the same and refuses a config that asks for ROS 2 with this message.
#include <stdexcept>

#include "omniloc/ros2_bridge.hpp"

namespace omniloc::ros2 {

struct Ros2Bridge::Impl {};

Ros2Bridge::Ros2Bridge(const Ros2Config&) {
  throw std::runtime_error(
      "ROS 2: this build has no Cyclone DDS (install cyclonedds-dev and cyclonedds-tools, then "
      "configure again)");
}
Ros2Bridge::~Ros2Bridge() = default;
void Ros2Bridge::publish(const Ros2Pose&) {}
std::optional<InitialPose> Ros2Bridge::take_initial_pose() {
  return std::nullopt;
}
std::uint64_t Ros2Bridge::published() const {
  return 0;
}
std::uint64_t Ros2Bridge::failed() const {
  return 0;
}

bool ros2_available() {
  return false;
}

}  // namespace omniloc::ros2
