// A consumer of the installed library: loads the installed FIRA field by name (OMNILOC_DATA_DIR
// points at share/omniloc), composes two poses and prints what it found, for check_install.sh to
// compare with the field file's numbers and a hand-computed composition. With --list-boards it
// lists the USB boards instead: never run by check_install.sh, but linked, so that libomniloc.a's
// private dependency libusb must reach the consumer's link line (the CMake export's LINK_ONLY
// items, `pkg-config --static`).
#include <cstdio>
#include <cstring>
#include <exception>

#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"
#include "omniloc/usb_transport.hpp"

int main(int argc, char** argv) {
  try {
    if (argc > 1 && std::strcmp(argv[1], "--list-boards") == 0) {
      std::printf("%zu FT2232H found\n", omniloc::find_usb_boards().size());
      return 0;
    }
    const omniloc::FieldGeometry field = omniloc::load_field("fira-robosot");
    const omniloc::Pose2 a{100.0, 50.0, 90.0};
    const omniloc::Pose2 b = omniloc::compose(a, omniloc::Pose2{10.0, 0.0, 0.0});
    std::printf("field %s %.0f x %.0f cm\n", field.name.c_str(), field.field_length_cm,
                field.field_width_cm);
    std::printf("compose %.1f %.1f %.1f\n", b.x_cm, b.y_cm, b.yaw_deg);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
}
