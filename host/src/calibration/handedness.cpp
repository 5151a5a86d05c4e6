// Which calibration frames can tell a mirrored camera from an unmirrored one (docs/CALIBRATION.md,
// "Handedness").
#include "handedness.hpp"

#include <cmath>

#include "omniloc/conventions.hpp"

namespace omniloc::detail {

MirrorAxes field_mirror_axes(const FieldGeometry& field) {
  // Every white point of a 2 cm grid (offset from the centre, so no sample falls on a line's exact
  // edge) against its reflection; a sample or two may differ by rounding at an edge, while the
  // smallest asymmetric feature, a 5 cm mark, covers about 20.
  const WhiteLineIndex lines(field);
  const Eigen::Vector2d c = field.centre_cm();
  constexpr double kStepCm = 2.0;
  long off_long = 0, off_halfway = 0;
  for (double x = kStepCm / 2 + 0.013; x < field.total_x_cm(); x += kStepCm) {
    for (double y = kStepCm / 2 + 0.017; y < field.total_y_cm(); y += kStepCm) {
      if (!lines.is_white({x, y})) continue;
      off_long += !lines.is_white({x, 2 * c.y() - y});
      off_halfway += !lines.is_white({2 * c.x() - x, y});
    }
  }
  constexpr long kRoundingSamples = 4;
  return {off_long <= kRoundingSamples, off_halfway <= kRoundingSamples};
}

std::optional<std::string> handedness_evidence(const std::vector<CalibrationFrame>& frames,
                                               const FieldGeometry& field, double separation_cm) {
  const MirrorAxes axes = field_mirror_axes(field);
  const Eigen::Vector2d c = field.centre_cm();
  for (const auto& f : frames) {
    const bool long_twin =
        axes.long_axis && 2.0 * std::abs(f.position_cm.y() - c.y()) < separation_cm;
    const bool halfway_twin =
        axes.halfway_line && 2.0 * std::abs(f.position_cm.x() - c.x()) < separation_cm;
    if (!long_twin && !halfway_twin) return f.name + " stands off the field's mirror axes";
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    for (std::size_t j = i + 1; j < frames.size(); ++j) {
      if (!frames[i].yaw_deg || !frames[j].yaw_deg) continue;
      const double d = std::abs(wrap_deg(*frames[j].yaw_deg - *frames[i].yaw_deg));
      if (d > 10.0 && d < 170.0)
        return frames[i].name + " and " + frames[j].name + " have known headings " +
               std::to_string(static_cast<int>(std::lround(d))) + " deg apart";
    }
  }
  return std::nullopt;
}

}  // namespace omniloc::detail
