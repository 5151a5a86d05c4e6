// Whether the frames of a calibration can tell the camera's handedness (internal to the
// calibration).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "omniloc/calibration.hpp"

namespace omniloc::detail {

/// What in the frames tells the camera's handedness, or none. A mirrored camera at a spot p sees
/// what an unmirrored one sees from p reflected about a mirror axis of the field's lines (the
/// reflection maps the lines onto themselves, and the camera's yaw offset is fitted): a frame
/// tells only when it stands far enough off every such axis that the two spots are `separation_cm`
/// apart. The heading of one frame does not tell (the yaw offset absorbs it), but two frames whose
/// known headings differ by other than 0 or 180 deg do: the reflection reverses the difference.
[[nodiscard]] std::optional<std::string> handedness_evidence(
    const std::vector<CalibrationFrame>& frames, const FieldGeometry& field, double separation_cm);

/// The field's mirror axes through its centre that map its lines onto themselves: the line
/// y = centre (the long axis) and the line x = centre (the halfway line). Measured on the lines,
/// not assumed: a field file may place marks off the axes.
struct MirrorAxes {
  bool long_axis = false, halfway_line = false;
};
[[nodiscard]] MirrorAxes field_mirror_axes(const FieldGeometry& field);

}  // namespace omniloc::detail
