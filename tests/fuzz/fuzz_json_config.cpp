// Harness: the JSON readers of the config layer, each through its real file entry point (the
// input is written to a scratch file first). Input: byte 0 picks the reader, the rest is the file:
//   0 field geometry (load_field: parse, validate, build the lines)   1 camera (load_camera)
//   2 robot (load_robot_config)   3 localizer (load_localizer_config)
//   4 omnilocd config (load_daemon_config)   5 a recording's meta.json (read_meta)
// Expected errors: ConfigError (RecordingError for meta.json), and its text must name the file.
// Anything the readers accept must validate again (or, for a field, have a usable carpet).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_common.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/config.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/robot_config.hpp"

namespace {

using omniloc::fuzz::fuzz_check;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const omniloc::fuzz::ScratchFile file("input.json");
  const auto& path =
      file.write(std::string_view(reinterpret_cast<const char*>(data + 1), size - 1));
  const std::string p = path.string();
  try {
    switch (data[0] % 6) {
      case 0: {
        const omniloc::FieldGeometry f = omniloc::load_field(p);
        fuzz_check(std::isfinite(f.total_x_cm()) && std::isfinite(f.total_y_cm()) &&
                       f.total_x_cm() > 0 && f.total_y_cm() > 0,
                   "a field without a finite, positive carpet was accepted");
        f.spec.validate("fuzz");
        (void)f.fingerprint();
        (void)omniloc::is_white(f, f.centre_cm());
        // The grid a database would be built on (GridSpec::covering at the daemon's default step):
        // its cell count must be an int that a machine can hold (1440 bytes a cell).
        const omniloc::GridSpec g = omniloc::GridSpec::covering(f, 10.0);
        fuzz_check(
            g.nx > 0 && g.ny > 0 && static_cast<long long>(g.nx) * g.ny <= 10'000'000,
            "an accepted field gives a database grid of no cells or of more than 10 million");
        break;
      }
      case 1:
        omniloc::load_camera(p).validate("fuzz");
        break;
      case 2:
        omniloc::load_robot_config(p).validate("fuzz");
        break;
      case 3:
        omniloc::load_localizer_config(p).validate("fuzz");
        break;
      case 4:
        omniloc::daemon::load_daemon_config(p).validate("fuzz");
        break;
      default:
        omniloc::read_meta(p).validate("fuzz");
        break;
    }
  } catch (const omniloc::ConfigError& e) {
    fuzz_check(std::string_view(e.what()).find(p) != std::string_view::npos,
               "a ConfigError that does not name the file");
  } catch (const omniloc::RecordingError& e) {
    fuzz_check(data[0] % 6 == 5, "a RecordingError from a config reader");
    fuzz_check(std::string_view(e.what()).find(p) != std::string_view::npos,
               "a RecordingError that does not name meta.json");
  }
  return 0;
}
