// The board's USB identity has one source, firmware/ft2232h_eeprom.conf (what `make -C firmware
// eeprom` writes into the FT2232H): the host must look for exactly what it says, and the reader of
// that file must refuse a broken one with the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "omniloc/usb_transport.hpp"
#include "omniloc_sim/ft2232h_eeprom.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

TEST(FirmwareEeprom, HostLooksForTheIdentityTheEepromGives) {
  const sim::EepromIdentity id = sim::read_eeprom_identity(OMNILOC_EEPROM_CONF);
  EXPECT_EQ(id.vendor_id, ftdi::kVid);
  EXPECT_EQ(id.product_id, ftdi::kPidFt2232h);
  EXPECT_EQ(id.product, UsbTransportOptions{}.product);
  EXPECT_EQ(id.channel_b_type, "UART");  // channel B is the FPGA's UART (docs/PROTOCOL.md)
  EXPECT_FALSE(id.manufacturer.empty());
  EXPECT_FALSE(id.serial.empty());
}

class EepromFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("omniloc_test_eeprom_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& text) {
    const fs::path p = dir_ / "eeprom.conf";
    std::ofstream(p) << text;
    return p;
  }
  std::string error_of(const std::string& text) {
    const fs::path p = write(text);
    try {
      (void)sim::read_eeprom_identity(p);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << "accepted:\n" << text;
    return {};
  }

  static constexpr const char* kGood =
      "# a comment\n"
      "vendor_id=0x0403   # trailing comment\n"
      "product_id = 24592\n"
      "manufacturer=\"ACME # robotics\"\n"
      "product=\"omniloc encoder board\"\n"
      "serial=\"OL000042\"\n"
      "\n"
      "chb_type=UART\n";

  fs::path dir_;
};

TEST_F(EepromFiles, ReadsKeysQuotesNumbersAndComments) {
  const sim::EepromIdentity id = sim::read_eeprom_identity(write(kGood));
  EXPECT_EQ(id.vendor_id, 0x0403);
  EXPECT_EQ(id.product_id, 0x6010);  // 24592 in decimal
  EXPECT_EQ(id.manufacturer, "ACME # robotics");  // a '#' inside quotes is not a comment
  EXPECT_EQ(id.product, "omniloc encoder board");
  EXPECT_EQ(id.serial, "OL000042");
  EXPECT_EQ(id.channel_b_type, "UART");
}

TEST_F(EepromFiles, BrokenFilesAreNamedWithTheLine) {
  const std::string file = (dir_ / "eeprom.conf").string();
  std::string good = kGood;

  EXPECT_EQ(error_of(good + "max_power 500\n"), file + ":9: expected key=value, got 'max_power 500'");
  std::string bad_vid = good;
  bad_vid.replace(bad_vid.find("0x0403"), 6, "0x04g3");
  EXPECT_EQ(error_of(bad_vid), file + ":2: vendor_id '0x04g3' is not a 16-bit number");
  EXPECT_EQ(error_of(good + "product=\"other\"\n"), file + ":9: 'product' given again (first on line 5)");
  EXPECT_EQ(error_of("vendor_id=0x0403\nproduct_id=0x16010\n" + good.substr(good.find("manufacturer"))),
            file + ":2: product_id '0x16010' is not a 16-bit number");
  EXPECT_EQ(error_of(good + "serial=\"OL0\n"), file + ":9: unterminated string in 'serial=\"OL0'");

  std::string no_product = good;
  no_product.erase(no_product.find("product="), std::string("product=\"omniloc encoder board\"\n").size());
  EXPECT_EQ(error_of(no_product), file + ": no 'product' key");

  const fs::path missing = dir_ / "absent.conf";
  try {
    (void)sim::read_eeprom_identity(missing);
    FAIL() << "read a file that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), missing.string() + ": cannot open the EEPROM configuration");
  }
}

}  // namespace
}  // namespace omniloc
