// UsbTransport against the emulated FT2232H (umockdev): open, configure, read the ID register,
// stream a second of windows, line-status errors, and an unplug in the middle of streaming. Run
// under `umockdev-wrapper` (CTest does).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <atomic>
#include <cstdio>
#include <string>
#include <thread>

#include "omniloc/board_client.hpp"
#include "omniloc/usb_transport.hpp"
#include "omniloc_sim/ft2232h_eeprom.hpp"
#include "omniloc_sim/ft2232h_model.hpp"
#include "omniloc_sim/reference_board.hpp"

namespace omniloc {
namespace {

namespace r = regmap;
using namespace std::chrono_literals;

std::array<std::int32_t, 4> script(std::uint32_t seq) {
  const auto s = static_cast<std::int32_t>(seq);
  return {s * 11, -s * 5, 300 - 7 * s, (s % 4) - 2};
}

/// A UART side that never says anything: the other FTDI device on the bus.
struct Mute final : sim::UartSide {
  void to_board(std::span<const std::uint8_t>) override {}
  std::size_t from_board(std::span<std::uint8_t>) override { return 0; }
};

/// The other FTDI device on the bus: a stock FT2232H breakout.
sim::Ft2232hConfig stock_ftdi_config() {
  sim::Ft2232hConfig c;
  c.address = 3;
  c.manufacturer = "FTDI";
  c.product = "Dual RS232-HS";
  c.serial = "FT123456";
  return c;
}

/// The identity the omniloc board's EEPROM gives it (firmware/ft2232h_eeprom.conf, its one source).
sim::EepromIdentity eeprom() {
  return sim::read_eeprom_identity(OMNILOC_EEPROM_CONF);
}

class UsbLink : public ::testing::Test {
 protected:
  // The omniloc board as its EEPROM makes it: the host, with its defaults, must find this one.
  UsbLink()
      : board({}, script),
        device(usb, board, sim::Ft2232hConfig::programmed_with(eeprom())),
        other(usb, mute, stock_ftdi_config()) {}
  static BoardClientOptions client_options() {
    BoardClientOptions o;
    o.response_timeout = 200ms;  // each emulated USB transfer costs ~1 ms
    return o;
  }

  sim::EmulatedUsb usb;
  sim::ReferenceBoard board;
  Mute mute;
  sim::Ft2232hModel device;
  sim::Ft2232hModel other;
};

TEST_F(UsbLink, FindsTheBoardAmongOtherFtdiDevices) {
  const auto boards = find_usb_boards();
  ASSERT_EQ(boards.size(), 2u);
  int omniloc = 0;
  for (const auto& b : boards) {
    EXPECT_TRUE(b.error.empty()) << b.error;
    if (b.is_omniloc) {
      ++omniloc;
      EXPECT_EQ(b.serial, eeprom().serial);
      EXPECT_EQ(b.manufacturer, eeprom().manufacturer);
      EXPECT_EQ(b.address, 2);
    } else {
      EXPECT_EQ(b.product, "Dual RS232-HS");
    }
  }
  EXPECT_EQ(omniloc, 1);
  UsbTransportOptions wrong;
  wrong.serial = "OL999999";
  try {
    UsbTransport t(wrong);
    FAIL() << "opened a board with the wrong serial";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportErrorKind::kNotFound);
    EXPECT_NE(std::string(e.what()).find("OL999999"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Dual RS232-HS"), std::string::npos) << e.what();
  }
}

TEST_F(UsbLink, ConfiguresChannelBAndReadsTheId) {
  UsbTransport t;
  const auto s = device.state();
  EXPECT_TRUE(s.driver_detached);
  EXPECT_TRUE(s.interface_claimed);
  EXPECT_TRUE(s.configured_as_uart());
  EXPECT_EQ(s.baud_value, 0x000C);  // 1 Mbaud
  EXPECT_EQ(s.baud_index, 0x0202);
  EXPECT_EQ(s.latency_ms, 1);
  for (const auto& c : s.control)
    EXPECT_TRUE(c.accepted) << "request " << int(c.request) << " stalled";
  EXPECT_TRUE(s.unhandled_ioctls.empty())
      << "first unhandled ioctl 0x" << std::hex << s.unhandled_ioctls.front();
  EXPECT_FALSE(other.state().interface_claimed);
  EXPECT_EQ(t.actual_baud(), 1'000'000u);
  EXPECT_EQ(t.board().serial, eeprom().serial);

  BoardClient client(t, client_options());
  EXPECT_EQ(client.read_register(r::kRegId), r::kIdValue);
  EXPECT_EQ(client.read_register(r::kRegVersion), r::kVersionValue);
  client.write_register(r::kRegFilter, 17);
  EXPECT_EQ(board.reg(r::kRegFilter), 17u);
  EXPECT_EQ(client.counters().retries, 0u);
  // Two READ_REQ and one WRITE_REQ crossed the bridge, nothing else.
  EXPECT_EQ(device.state().bulk_out_bytes, 2 * protocol::frame_bytes(1) + protocol::frame_bytes(5));
}

TEST_F(UsbLink, StreamsASecondOfWindows) {
  UsbTransport t;
  BoardClient client(t, client_options());
  client.write_register(r::kRegControl, r::kControlEnable.mask());
  client.set_streaming(true);
  // The board captures a window every 10 ms of wall time, as the real one does.
  std::thread clock([&] {
    for (int i = 0; i < 100; ++i) {
      std::this_thread::sleep_for(10ms);
      board.run_windows(1);
    }
  });
  std::vector<protocol::Window> got;
  while (got.size() < 100) {
    const auto w = client.poll_telemetry(1000ms);
    if (!w) break;
    got.push_back(*w);
  }
  clock.join();
  ASSERT_EQ(got.size(), 100u);
  for (std::uint32_t i = 0; i < 100; ++i) {
    EXPECT_EQ(got[i].seq, i + 1);
    EXPECT_EQ(got[i].count, script(i + 1)) << "window " << i + 1;
  }
  EXPECT_EQ(client.decoder_counters().telemetry_lost, 0u);
  EXPECT_EQ(client.decoder_counters().resync_bytes, 0u);

  // A burst larger than one 512-byte packet: several packets in one transfer, each with its own two
  // status bytes that must not leak into the data.
  board.run_windows(60);  // 60 x 31 = 1860 bytes
  for (std::uint32_t seq = 101; seq <= 160; ++seq) {
    const auto w = client.poll_telemetry(1000ms);
    ASSERT_TRUE(w.has_value()) << seq;
    EXPECT_EQ(w->seq, seq);
    EXPECT_EQ(w->count, script(seq));
  }
  EXPECT_EQ(client.decoder_counters().resync_bytes, 0u);
  const auto s = device.state();
  EXPECT_GT(s.bulk_in_packets, s.status_only_packets + 4);  // the burst took >= 4 full packets
  const auto ts = t.status();
  EXPECT_EQ(ts.counters.bytes_read, s.bulk_in_bytes);
  // The bridge keeps answering bulk-IN polls with status-only packets; the ones whose completion
  // the transport's event thread has not handled yet (at most its transfers in flight) are not
  // counted.
  EXPECT_LE(ts.counters.packets_in, s.bulk_in_packets);
  EXPECT_LE(s.bulk_in_packets - ts.counters.packets_in,
            static_cast<std::uint64_t>(UsbTransportOptions{}.in_transfers));
  EXPECT_EQ(ts.counters.line_framing, 0u);
}

TEST_F(UsbLink, CountsLineStatusErrors) {
  UsbTransport t;
  device.inject_line_status(0x02 | 0x08, 3);  // OE and FE on three packets
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  std::array<std::uint8_t, 64> buf{};
  while (t.status().counters.line_framing < 3 && std::chrono::steady_clock::now() < deadline) {
    (void)t.read(buf, 5ms);
  }
  const auto c = t.status().counters;
  EXPECT_EQ(c.line_framing, 3u);
  EXPECT_EQ(c.line_overrun, 3u);
  EXPECT_EQ(c.line_parity, 0u);
  EXPECT_EQ(c.line_break, 0u);
}

TEST_F(UsbLink, ReportsUnplugInTheMiddleOfStreaming) {
  UsbTransport t;
  BoardClient client(t, client_options());
  client.write_register(r::kRegControl, r::kControlEnable.mask() | r::kControlStream.mask());
  std::atomic<bool> stop{false};
  std::thread clock([&] {
    for (int i = 0; i < 50 && !stop; ++i) {
      std::this_thread::sleep_for(10ms);
      board.run_windows(1);
    }
    device.unplug();
  });
  std::uint32_t received = 0;
  bool gone = false;
  try {
    while (received < 1000) {
      const auto w = client.poll_telemetry(1000ms);
      if (!w) break;
      ++received;
      ASSERT_EQ(w->seq, received);
      ASSERT_EQ(w->count, script(received));
    }
  } catch (const TransportError& e) {
    gone = e.kind() == TransportErrorKind::kDeviceGone;
    EXPECT_NE(std::string(e.what()).find("LIBUSB_ERROR_NO_DEVICE"), std::string::npos) << e.what();
  }
  stop = true;
  clock.join();
  EXPECT_TRUE(gone) << "unplug not reported; " << received << " windows received";
  // Every frame the bridge delivered before the unplug was accepted (the last window may have been
  // captured after the bridge's last packet: those bytes die with the cable). The one WRITE_ACK
  // aside, the bridge carried only telemetry.
  const auto delivered =
      device.state().bulk_in_bytes - protocol::frame_bytes(regmap::kFrameWriteAckBodyBytes);
  EXPECT_EQ(delivered % protocol::frame_bytes(regmap::kFrameTelemetryBodyBytes), 0u);
  EXPECT_EQ(received, delivered / protocol::frame_bytes(regmap::kFrameTelemetryBodyBytes));
  EXPECT_GE(received, 10u);  // streaming really ran before the unplug
  EXPECT_TRUE(t.status().device_gone);
  try {
    t.write(protocol::encode(protocol::ReadReq{r::kRegId}));
    FAIL() << "write after unplug succeeded";
  } catch (const TransportError& e) {
    EXPECT_EQ(e.kind(), TransportErrorKind::kDeviceGone) << e.what();
  }
}

#ifdef OMNILOC_CLI_PATH
/// Runs the omniloc command line as a child process; it inherits umockdev's preload and testbed, so
/// it sees the emulated bus. Returns {exit status, stdout + stderr}.
std::pair<int, std::string> run_cli(const std::string& args) {
  const std::string cmd = std::string(OMNILOC_CLI_PATH) + " " + args + " 2>&1";
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, "popen failed"};
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

std::string row(const protocol::Window& w) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%10u %11d %11d %11d %11d", w.seq, w.count[0], w.count[1],
                w.count[2], w.count[3]);
  return buf;
}

/// Writes a register of the board model directly, as the host would, and drops the acknowledgement.
void poke(sim::ReferenceBoard& board, std::uint8_t addr, std::uint32_t value) {
  board.to_board(protocol::encode(protocol::WriteReq{addr, value}));
  std::array<std::uint8_t, 64> ack{};
  ASSERT_EQ(board.from_board(ack), protocol::frame_bytes(1));
}

TEST_F(UsbLink, ProbeOncePrintsIdStatusAndASnapshot) {
  poke(board, r::kRegControl, r::kControlEnable.mask());
  board.run_windows(3);
  const auto [rc, out] = run_cli("probe --once");
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("<- omniloc board"), std::string::npos) << out;
  EXPECT_NE(out.find("Dual RS232-HS"), std::string::npos) << out;
  EXPECT_NE(out.find("ID 0x4F4D4E4C  register map 0.3.0"), std::string::npos) << out;
  EXPECT_NE(out.find("CONFIG channels 4 (the bitstream counts 4 wheels)"), std::string::npos)
      << out;
  EXPECT_NE(out.find("GYRO_STATE running 1 absent 0 faults 0 (the ICM-42688-P is read)"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("CONTROL 0x00000001 (ENABLE 1"), std::string::npos) << out;
  EXPECT_NE(out.find(row(board.windows().back())), std::string::npos) << out;
}

TEST_F(UsbLink, ProbeStreamsALiveTableAndRestoresControl) {
  poke(board, r::kRegControl, r::kControlEnable.mask());
  std::atomic<bool> stop{false};
  std::thread clock([&] {
    while (!stop) {
      std::this_thread::sleep_for(10ms);
      board.run_windows(1);
    }
  });
  const auto [rc, out] = run_cli("probe --seconds 1");
  stop = true;
  clock.join();
  EXPECT_EQ(rc, 0) << out;
  const auto windows = board.windows();
  int rows = 0;
  for (const auto& w : windows) {
    if (w.seq % 10 == 0 && out.find(row(w)) != std::string::npos) ++rows;
  }
  EXPECT_GE(rows, 3) << out;
  EXPECT_EQ(board.reg(r::kRegControl), r::kControlEnable.mask());  // STREAM switched off again
}

TEST(UsbProbe, SaysSoWhenNoBoardIsAttached) {
  sim::EmulatedUsb usb;
  Mute mute;
  sim::Ft2232hModel other(usb, mute, stock_ftdi_config());
  const auto [rc, out] = run_cli("probe --once");
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("no omniloc board found"), std::string::npos) << out;
}
#endif

}  // namespace
}  // namespace omniloc
