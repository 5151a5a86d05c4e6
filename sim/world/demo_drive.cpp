// The drive of `omniloc-sim demo` (demo_drive.hpp).
#include "omniloc_sim/demo_drive.hpp"

namespace omniloc::sim {

DemoDrive demo_drive(double duration_s) {
  DemoDrive d;
  const MotionLimits lim{120.0, 240.0, 120.0, 240.0};
  auto& t = d.trajectory;
  // The field lines are at x = 75 / 675 and y = 75 / 475: the boundary legs run 5-10 cm inside
  // them, where the paper's image-only method fails (its Fig. 18 boundary points).
  t.line_to({665.0, 275.0}, 0.0, lim);   // to the right goal line
  t.line_to({670.0, 470.0}, 90.0, lim);  // along it to the top-right corner
  t.line_to({80.0, 470.0}, 180.0, lim);  // along the top line
  t.line_to({80.0, 80.0}, 270.0, lim);   // along the left goal line
  t.line_to({670.0, 80.0}, 360.0, lim);  // along the bottom line
  t.line_to({450.0, 220.0}, 360.0, lim);
  t.wait(0.6);
  d.kidnap_s = t.duration_s() - 0.3;
  d.kidnap_to = Pose2{250.0, 360.0, 90.0};
  // +x of the old frame becomes +y here: this leg ends near (250, 440).
  t.line_to({530.0, 220.0}, 360.0, lim);
  if (t.duration_s() < duration_s) t.wait(duration_s - t.duration_s());
  return d;
}

}  // namespace omniloc::sim
