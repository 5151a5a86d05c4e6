// `omniloc probe`: finds omniloc boards on USB, prints ID, version, status and the gyro's state,
// then a live table of window counts and link errors (or one snapshot with --once).
#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "omniloc/board_session.hpp"
#include "omniloc/usb_transport.hpp"

namespace omniloc::cli {

namespace {

// SIGINT ends the live table cleanly (CONTROL restored). A signal handler can only reach a
// process-wide flag; nothing else in the program touches it.
std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) {
  g_interrupted = true;
}

struct ProbeArgs {
  bool once = false;
  bool enable = false;
  std::uint64_t seconds = 0;
  UsbTransportOptions opt;
};

void print_row(const protocol::Window& w, const protocol::DecoderCounters& dc,
               const TransportCounters& tc, std::uint64_t retries) {
  std::printf("%10u %11d %11d %11d %11d  0x%X  0x%02X %7llu %7llu %7llu %7llu %7llu\n", w.seq,
              w.count[0], w.count[1], w.count[2], w.count[3], w.dir, w.status,
              static_cast<unsigned long long>(dc.telemetry_lost),
              static_cast<unsigned long long>(dc.bad_crc + dc.bad_length + dc.unknown_type),
              static_cast<unsigned long long>(dc.resync_bytes),
              static_cast<unsigned long long>(tc.line_framing + tc.line_overrun + tc.line_parity +
                                              tc.line_break),
              static_cast<unsigned long long>(retries));
}

void print_header() {
  std::printf("%10s %11s %11s %11s %11s  %3s  %4s %7s %7s %7s %7s %7s\n", "seq", "count0", "count1",
              "count2", "count3", "dir", "stat", "lost", "badfrm", "resync", "lineerr", "retries");
}

// The FT2232H boards on USB, one line each. False when none is an omniloc board (said on stderr).
bool list_boards(const UsbTransportOptions& opt) {
  const auto boards = find_usb_boards(opt.product);
  int found = 0;
  for (const auto& b : boards) {
    std::printf("FT2232H %03d/%03d  product '%s'  serial '%s'%s%s\n", b.bus, b.address,
                b.product.c_str(), b.serial.c_str(), b.is_omniloc ? "  <- omniloc board" : "",
                b.error.empty() ? "" : ("  (" + b.error + ")").c_str());
    found += b.is_omniloc ? 1 : 0;
  }
  if (found == 0) {
    std::fprintf(
        stderr,
        "omniloc probe: no omniloc board found: no FT2232H (0403:6010) with product \"%s\" on USB "
        "(%zu other FT2232H seen). Is the board plugged in, its EEPROM written (firmware/), and "
        "the "
        "USB device readable by this user?\n",
        opt.product.c_str(), boards.size());
    return false;
  }
  return true;
}

// The board's identity and registers as read (ID, version, CONFIG, CONTROL, STATUS, link and
// channel errors, the gyro's state), warning when its register map differs from the host's.
void print_registers(BoardSession& session) {
  namespace r = regmap;
  BoardClient& client = session.client();
  const BoardIdentity& ident = session.identity();
  const std::uint32_t id = ident.id;
  const std::uint32_t version = ident.version;
  const std::uint32_t control = ident.control;
  const std::uint32_t period = ident.period_cycles;
  const std::uint32_t status = client.read_register(r::kRegStatus);
  const std::uint32_t link = client.read_register(r::kRegLinkErrors);
  std::printf("%s\n", session.transport().status().description.c_str());
  std::printf("ID 0x%08X  register map %u.%u.%u (host speaks %u.%u.%u)\n", id,
              r::kVersionMajor.get(version), r::kVersionMinor.get(version),
              r::kVersionPatch.get(version), r::kVersionMajor.get(r::kVersionValue),
              r::kVersionMinor.get(r::kVersionValue), r::kVersionPatch.get(r::kVersionValue));
  std::printf("CONFIG channels %d (the bitstream counts %d wheels)\n", ident.channels,
              ident.channels);
  std::printf(
      "CONTROL 0x%08X (ENABLE %u, DECODE %u, STREAM %u)  PERIOD %u cycles  STATUS 0x%08X "
      "(ILLEGAL 0x%X, OVERRUN %u, BAD_WRITE %u)\n",
      control, r::kControlEnable.get(control), r::kControlDecode.get(control),
      r::kControlStream.get(control), period, status, r::kStatusIllegal.get(status),
      r::kStatusOverrun.get(status), r::kStatusBadWrite.get(status));
  std::printf("LINK_ERRORS framing %u overrun %u  ERROR_COUNT", r::kLinkErrorsFraming.get(link),
              r::kLinkErrorsOverrun.get(link));
  for (int ch = 0; ch < r::kChannels; ++ch) {
    std::printf(" %u", client.read_register(static_cast<std::uint8_t>(r::kRegErrorCount0 + ch)));
  }
  std::printf("\n");
  const std::uint32_t gyro = client.read_register(r::kRegGyroState);
  std::printf("GYRO_STATE running %u absent %u faults %u (%s)\n", r::kGyroStateRunning.get(gyro),
              r::kGyroStateAbsent.get(gyro), r::kGyroStateFaults.get(gyro),
              r::kGyroStateRunning.get(gyro) ? "the ICM-42688-P is read"
              : r::kGyroStateAbsent.get(gyro)
                  ? "no gyro answers on PMOD1B: the heading comes from the wheels"
                  : "the gyro is starting");
  if (version_differs(ident)) {
    std::fprintf(stderr, "warning: the board's register map differs from the host's\n");
  }
}

// Streams telemetry, a row every 10th window, for `seconds` (0: until Ctrl-C). Returns the exit
// status: 1 when the device is gone.
int stream_rows(BoardClient& client, Transport& usb, std::uint64_t seconds) {
  std::signal(SIGINT, on_sigint);
  client.set_streaming(
      true);  // streaming on here, not in BoardSession: probe keeps the board's DECODE
  print_header();
  const auto until =
      std::chrono::steady_clock::now() + std::chrono::seconds(static_cast<std::int64_t>(seconds));
  try {
    while (!g_interrupted && (seconds == 0 || std::chrono::steady_clock::now() < until)) {
      const auto w = client.poll_telemetry(std::chrono::milliseconds(500));
      if (!w) {
        std::fprintf(stderr, "no telemetry for 500 ms\n");
        continue;
      }
      if (w->seq % 10 == 0) {
        print_row(*w, client.decoder_counters(), usb.status().counters, client.counters().retries);
        std::fflush(stdout);
      }
    }
  } catch (const TransportError& e) {
    std::fprintf(stderr, "omniloc probe: %s\n", e.what());
    return 1;  // the device is gone: nothing to restore
  }
  return 0;
}

int run_probe(const ProbeArgs& a) {
  const UsbTransportOptions& opt = a.opt;
  if (!list_boards(opt)) return 1;
  namespace r = regmap;
  BoardSessionOptions so;
  so.configure = false;  // look, do not touch: CONTROL changes only with --enable, and is restored
  BoardSession session(std::make_unique<UsbTransport>(opt), so);
  BoardClient& client = session.client();
  Transport& usb = session.transport();
  const std::uint32_t control = session.identity().control;
  print_registers(session);
  if (a.once) {
    const auto w = client.snapshot();
    print_header();
    print_row(w, client.decoder_counters(), usb.status().counters, client.counters().retries);
    return 0;
  }
  if (!r::kControlEnable.get(control)) {
    if (!a.enable) {
      std::fprintf(
          stderr,
          "CONTROL.ENABLE is 0: the board captures no windows; run with --enable to set it\n");
      return 1;
    }
    client.write_register(r::kRegControl, r::kControlEnable.put(control, 1));
  }
  if (stream_rows(client, usb, a.seconds) != 0) return 1;
  client.write_register(r::kRegControl, control);  // streaming and ENABLE as they were
  std::signal(SIGINT, SIG_DFL);
  return 0;
}

}  // namespace

Subcommand add_probe(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "probe", "find omniloc boards on USB, print ID/version/status and live counts");
  auto a = std::make_shared<ProbeArgs>();
  app->add_flag("--once", a->once, "one snapshot, then exit");
  app->add_option("--serial", a->opt.serial, "the board's USB serial")
      ->default_str("the first omniloc board");
  add_number_option(*app, "--baud", a->opt.baud, "the board's UART rate", 1u, 12'000'000u);
  app->add_flag("--enable", a->enable, "set CONTROL.ENABLE if it is off (it is restored on exit)");
  add_number_option(*app, "--seconds", a->seconds, "stream this long; 0: until Ctrl-C",
                    std::uint64_t{0}, std::uint64_t{31'536'000});
  app->footer(
      "Finds omniloc encoder boards (FT2232H 0403:6010, product \"omniloc encoder board\"), prints "
      "ID, version\n"
      "and status, then streams windows and prints a table of counts and errors every 10 windows "
      "until Ctrl-C\n"
      "(or --seconds N). Exit status: 0 success, 1 no board or link failure, 2 bad usage.");
  return {app, [a] { return run_probe(*a); }};
}

}  // namespace omniloc::cli
