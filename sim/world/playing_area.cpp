// Playing areas from field files (playing_area.hpp).
#include "omniloc_sim/playing_area.hpp"

namespace omniloc::sim {

PlayingArea playing_area(const FieldGeometry& field, double robot_half_size_cm) {
  PlayingArea a;
  a.world_x_cm = field.total_x_cm();
  a.world_y_cm = field.total_y_cm();
  a.x_min_cm = field.border_cm;
  a.x_max_cm = field.border_cm + field.field_length_cm;
  a.y_min_cm = field.border_cm;
  a.y_max_cm = field.border_cm + field.field_width_cm;
  a.robot_half_size_cm = robot_half_size_cm;
  return a;
}

const PlayingArea& fira_robosot_area() {
  static const PlayingArea area = playing_area(load_field("fira-robosot"));
  return area;
}

}  // namespace omniloc::sim
