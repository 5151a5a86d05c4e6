// The only field geometry the world simulator needs: where the robot may drive, taken from a field
// file (common/fields/*.json, the one source of the field's size) so the simulator drives on any
// field the localizer knows: FIRA RoboSot, RoboCup MSL, a team's own.
#pragma once

#include "omniloc/field.hpp"

namespace omniloc::sim {

/// A playing field inside its border, in field coordinates (cm).
struct PlayingArea {
  double world_x_cm = 0.0;  ///< carpet, border included
  double world_y_cm = 0.0;
  double x_min_cm = 0.0;  ///< the outer field lines
  double x_max_cm = 0.0;
  double y_min_cm = 0.0;
  double y_max_cm = 0.0;
  double robot_half_size_cm = 20.0;  ///< the paper's robot is 40 x 40 cm

  [[nodiscard]] double centre_x_cm() const { return 0.5 * (x_min_cm + x_max_cm); }
  [[nodiscard]] double centre_y_cm() const { return 0.5 * (y_min_cm + y_max_cm); }
};

/// The playing area of `field`.
[[nodiscard]] PlayingArea playing_area(const FieldGeometry& field,
                                       double robot_half_size_cm = 20.0);

/// The FIRA RoboSot area, from common/fields/fira-robosot.json (loaded once): the simulator's
/// default.
[[nodiscard]] const PlayingArea& fira_robosot_area();

}  // namespace omniloc::sim
