// The board's USB identity has one source, firmware/ft2232h_eeprom.conf (what `make -C firmware
// eeprom` writes into the FT2232H): the host must look for exactly what it says, and the reader of
// that file must refuse a broken one with the file and line.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

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

// The udev rule shipped for the board (packaging/udev/60-omniloc.rules) matches the same identity.
// There is no udevd in CI, so the rule is checked here: every line is a comment, or comma-separated
// KEY[{attribute}]OP"value" items with keys and operators udev knows (udev(7)), and the one
// matching rule names exactly the EEPROM's VID, PID and product and grants the daemon's group
// access.
TEST(FirmwareEeprom, UdevRuleMatchesTheEepromIdentity) {
  const sim::EepromIdentity id = sim::read_eeprom_identity(OMNILOC_EEPROM_CONF);
  std::ifstream in(OMNILOC_UDEV_RULE);
  ASSERT_TRUE(in) << OMNILOC_UDEV_RULE;
  const std::regex item(R"re(^([A-Z]+)(\{([A-Za-z_]+)\})?(==|!=|\+=|-=|:=|=)"([^"]*)"$)re");
  const std::vector<std::string> known{"ACTION", "SUBSYSTEM", "ENV",  "ATTR", "MODE",
                                       "GROUP",  "SYMLINK",   "GOTO", "LABEL"};
  std::vector<std::map<std::string, std::string>> rules;  // "KEY{attr}OP" -> value
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::map<std::string, std::string> rule;
    std::stringstream items(line);
    for (std::string it; std::getline(items, it, ',');) {
      it.erase(0, it.find_first_not_of(' '));
      std::smatch m;
      ASSERT_TRUE(std::regex_match(it, m, item))
          << OMNILOC_UDEV_RULE << ":" << n << ": not KEY{attr}OP\"value\": " << it;
      ASSERT_NE(std::find(known.begin(), known.end(), m[1].str()), known.end())
          << ":" << n << ": unknown key " << m[1];
      rule[m[1].str() + (m[2].matched ? m[2].str() : "") + m[4].str()] = m[5].str();
    }
    rules.push_back(rule);
  }
  char vid[8], pid[8];
  std::snprintf(vid, sizeof vid, "%04x", id.vendor_id);
  std::snprintf(pid, sizeof pid, "%04x", id.product_id);
  int matching = 0;
  for (const auto& r : rules) {
    if (!r.contains("ATTR{idVendor}==")) continue;
    ++matching;
    EXPECT_EQ(r.at("ATTR{idVendor}=="), vid);
    EXPECT_EQ(r.at("ATTR{idProduct}=="), pid);
    EXPECT_EQ(r.at("ATTR{product}=="), id.product);
    EXPECT_EQ(r.at("SUBSYSTEM=="), "usb");
    EXPECT_EQ(r.at("MODE="), "0660");
    EXPECT_EQ(r.at("GROUP="), "plugdev");  // the service's SupplementaryGroups (packaging/systemd)
  }
  EXPECT_EQ(matching, 1);
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
  EXPECT_EQ(id.product_id, 0x6010);               // 24592 in decimal
  EXPECT_EQ(id.manufacturer, "ACME # robotics");  // a '#' inside quotes is not a comment
  EXPECT_EQ(id.product, "omniloc encoder board");
  EXPECT_EQ(id.serial, "OL000042");
  EXPECT_EQ(id.channel_b_type, "UART");
}

TEST_F(EepromFiles, BrokenFilesAreNamedWithTheLine) {
  const std::string file = (dir_ / "eeprom.conf").string();
  std::string good = kGood;

  EXPECT_EQ(error_of(good + "max_power 500\n"),
            file + ":9: expected key=value, got 'max_power 500'");
  std::string bad_vid = good;
  bad_vid.replace(bad_vid.find("0x0403"), 6, "0x04g3");
  EXPECT_EQ(error_of(bad_vid), file + ":2: vendor_id '0x04g3' is not a 16-bit number");
  EXPECT_EQ(error_of(good + "product=\"other\"\n"),
            file + ":9: 'product' given again (first on line 5)");
  EXPECT_EQ(
      error_of("vendor_id=0x0403\nproduct_id=0x16010\n" + good.substr(good.find("manufacturer"))),
      file + ":2: product_id '0x16010' is not a 16-bit number");
  EXPECT_EQ(error_of(good + "serial=\"OL0\n"), file + ":9: unterminated string in 'serial=\"OL0'");

  std::string no_product = good;
  no_product.erase(no_product.find("product="),
                   std::string("product=\"omniloc encoder board\"\n").size());
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
