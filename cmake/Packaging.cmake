# The robot's Debian package (CPack DEB; `make package` = scripts/package.sh, CTest debian_package):
# omniloc_<version>_<arch>.deb holding whatever the install() rules install, under /usr: bin/omniloc,
# bin/omnilocd, lib/libomniloc.a with include/omniloc/, the CMake package and the pkg-config file,
# share/omniloc/ (the data, found by the programs as <exe>/../share/omniloc), the systemd unit
# (lib/systemd/system/omnilocd.service, ExecStart=/usr/bin/omnilocd) and the udev rule
# (lib/udev/rules.d/60-omniloc.rules). Depends is computed by dpkg-shlibdeps from the programs'
# dynamic libraries (OpenCV, libusb, libsystemd, and Cyclone DDS / cpp-httplib when built in).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME omniloc)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "omniloc")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "omni-vision self-localization for an omni-wheel soccer robot (omniloc, omnilocd)")
set(CPACK_PACKAGE_DESCRIPTION
    "The robot's side of omniloc: the localization daemon omnilocd (omni camera + FPGA encoder
board -> UDP poses; a systemd service), the command line omniloc (probe, builddb, replay,
locate, ctl), the field, camera, robot and daemon data files, the udev rule for the encoder
board, and the C++ library libomniloc.a with its headers, CMake package and pkg-config file.")
# The team's own maintainer and homepage go here (or -DOMNILOC_PACKAGE_MAINTAINER=... at configure time).
set(OMNILOC_PACKAGE_MAINTAINER "omniloc maintainers <maintainers@omniloc.invalid>"
    CACHE STRING "Maintainer field of the Debian package")
set(OMNILOC_PACKAGE_HOMEPAGE "https://omniloc.invalid/" CACHE STRING "Homepage field of the Debian package")
set(CPACK_PACKAGE_CONTACT "${OMNILOC_PACKAGE_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${OMNILOC_PACKAGE_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "${OMNILOC_PACKAGE_HOMEPAGE}")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # omniloc_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_RELEASE "")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# What a program built against the installed library (find_package / pkg-config) also needs.
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
    "libeigen3-dev, libopencv-dev, nlohmann-json3-dev, libusb-1.0-0-dev, libsystemd-dev")
# The unit's ExecStart is written at install time from CMAKE_INSTALL_PREFIX (root CMakeLists.txt):
# install with the prefix /usr into a DESTDIR staging folder, so that it says /usr/bin/omnilocd.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
# postinst / prerm / postrm: reload systemd and udev when they run (not in a chroot or container),
# stop the service before removal; the service is never enabled by the package.
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${CMAKE_CURRENT_SOURCE_DIR}/packaging/debian/postinst
    ${CMAKE_CURRENT_SOURCE_DIR}/packaging/debian/prerm
    ${CMAKE_CURRENT_SOURCE_DIR}/packaging/debian/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
