// The scripted drive of `omniloc-sim demo`: every boundary of the FIRA field, a wheel slip and a
// kidnapping (checked against the world simulator by test_demo_drive).
#pragma once

#include "omniloc/conventions.hpp"
#include "omniloc_sim/trajectory.hpp"

namespace omniloc::sim {

/// The drive of `omniloc-sim demo`: from the centre to the right goal line, then along all four
/// boundary lines (5-10 cm inside them), back towards the middle, a kidnapping while
/// stopped (carried 250 cm and turned 90 degrees), then a last leg driven from where the robot was
/// put down (the world moves the rest of the reference rigidly with it), padded to duration_s.
struct DemoDrive {
  Trajectory trajectory{"demo", {375.0, 275.0, 0.0}};
  double kidnap_s = 0.0;
  Pose2 kidnap_to;
  double slip_s = 8.0;  ///< wheel 2 slips from here for 0.5 s
};

[[nodiscard]] DemoDrive demo_drive(double duration_s = 30.0);

}  // namespace omniloc::sim
