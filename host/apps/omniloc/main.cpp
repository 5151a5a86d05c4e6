// `omniloc`: the command line of the omniloc host library (the robot's tools; the simulator's
// `demo` and `bench paper` are in `omniloc-sim`, sim/apps/omniloc_sim).
#include "command_table.hpp"
#include "commands.hpp"

namespace {

constexpr omniloc::cli::CommandEntry kCommands[] = {
    {"version", "print the host version and the register-map version it speaks", omniloc::cli::cmd_version},
    {"regmap", "print the register map the host was built against", omniloc::cli::cmd_regmap},
    {"probe", "find omniloc boards on USB, print ID/version/status and live counts", omniloc::cli::cmd_probe},
    {"builddb", "build the vision feature database (field x camera x grid) with progress", omniloc::cli::cmd_builddb},
    {"replay", "run the localizer over a recording directory, write poses.csv, errors vs truth", omniloc::cli::cmd_replay},
    {"locate", "one frame to a pose: the localizer's global search and acceptance, JSON and overlay", omniloc::cli::cmd_locate},
    {"ctl", "talk to a running omnilocd: status, set_pose, set_side, relocalize, record start|stop", omniloc::cli::cmd_ctl},
#ifdef OMNILOC_WITH_CALIBRATION
    {"calibrate", "estimate the camera (centre, mapping, yaw, mask) from frames at known poses", omniloc::cli::cmd_calibrate},
#endif
};

}  // namespace

int main(int argc, char** argv) { return omniloc::cli::run_command_table(argc, argv, "omniloc", kCommands); }
