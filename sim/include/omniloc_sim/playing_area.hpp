// The only field geometry the world simulator needs: where the robot may drive. The full line
// geometry (for the camera) lives in host/include/omniloc/field.hpp; these bounds are the single
// place in sim/world that knows the field's size.
#pragma once

namespace omniloc::sim {

/// FIRA RoboSot: a 600 x 400 cm playing field inside a 75 cm border, in field coordinates (cm).
struct PlayingArea {
  double world_x_cm = 750.0;
  double world_y_cm = 550.0;
  double x_min_cm = 75.0;
  double x_max_cm = 675.0;
  double y_min_cm = 75.0;
  double y_max_cm = 475.0;
  double robot_half_size_cm = 20.0;  ///< the paper's robot is 40 x 40 cm
};

inline constexpr PlayingArea kFiraRoboSot{};

}  // namespace omniloc::sim
