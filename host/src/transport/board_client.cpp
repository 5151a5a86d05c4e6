// BoardClient: request/response matching, retries, and the telemetry queue.
#include "omniloc/board_client.hpp"

#include <array>
#include <cstdio>

namespace omniloc {

namespace {

std::string hex8(std::uint8_t v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "0x%02X", v);
  return buf;
}

const char* expect_name(int e) {
  switch (e) {
    case 0:
      return "read of";
    case 1:
      return "write of";
    default:
      return "snapshot via";
  }
}

}  // namespace

BoardClient::BoardClient(Transport& transport, BoardClientOptions options)
    : transport_(transport), options_(options) {
  if (options_.attempts < 1)
    throw std::invalid_argument("BoardClientOptions.attempts must be >= 1");
  if (options_.response_timeout.count() <= 0) {
    throw std::invalid_argument("BoardClientOptions.response_timeout must be positive");
  }
}

void BoardClient::queue_telemetry(const protocol::Window& w) {
  if (telemetry_.size() >= options_.telemetry_queue && !telemetry_.empty()) {
    telemetry_.pop_front();
    ++counters_.telemetry_dropped;
  }
  telemetry_.push_back(w);
}

void BoardClient::drain_input() {
  // Answers that arrived after their request timed out would otherwise be taken for the answer to
  // the next request; take what is already here (telemetry is kept) before sending.
  std::array<std::uint8_t, 4096> buf{};
  while (true) {
    while (auto f = decoder_.next()) {
      if (auto* t = std::get_if<protocol::Telemetry>(&*f)) {
        queue_telemetry(t->window);
      } else {
        ++counters_.unexpected_frames;
      }
    }
    const std::size_t n = transport_.read(buf, std::chrono::milliseconds(0));
    if (n == 0) return;
    decoder_.feed(std::span<const std::uint8_t>(buf.data(), n));
  }
}

std::optional<protocol::Frame> BoardClient::next_frame(
    std::chrono::steady_clock::time_point deadline) {
  std::array<std::uint8_t, 4096> buf{};
  bool last_try = false;
  while (true) {
    if (auto f = decoder_.next()) return f;
    if (last_try) return std::nullopt;
    const auto now = transport_.now();
    // Past the deadline, one non-blocking read still runs: a zero timeout means "what is already
    // here".
    std::chrono::milliseconds wait{0};
    if (now >= deadline) {
      last_try = true;
    } else {
      // Round up so that a sub-millisecond remainder still waits instead of spinning.
      wait = std::chrono::ceil<std::chrono::milliseconds>(deadline - now);
    }
    const std::size_t n = transport_.read(buf, wait);
    decoder_.feed(std::span<const std::uint8_t>(buf.data(), n));
  }
}

protocol::Frame BoardClient::transact(const protocol::Frame& request, Expect expect,
                                      std::uint8_t addr) {
  using namespace protocol;
  ++counters_.requests;
  const auto bytes = encode(request);
  const std::string what =
      std::string(expect_name(static_cast<int>(expect))) + " register " + register_name(addr);
  for (int attempt = 0; attempt < options_.attempts; ++attempt) {
    if (attempt > 0) ++counters_.retries;
    drain_input();
    transport_.write(bytes);
    const auto deadline = transport_.now() + options_.response_timeout;
    bool resend = false;
    while (!resend) {
      auto f = next_frame(deadline);
      if (!f) {
        ++counters_.timeouts;
        break;
      }
      if (auto* t = std::get_if<Telemetry>(&*f)) {
        queue_telemetry(t->window);
        continue;
      }
      if (auto* e = std::get_if<ErrorResp>(&*f)) {
        if (e->code == regmap::kErrBadCrc || e->code == regmap::kErrMalformed) {
          // Our request was damaged on the way: the board did nothing, so sending it again is safe.
          ++counters_.board_rejected;
          resend = true;
          continue;
        }
        if (expect != Expect::kSnapshot && e->detail != addr) {
          ++counters_.unexpected_frames;  // a late answer to an earlier request
          continue;
        }
        throw BoardError("board refused " + what + ": " + std::string(error_name(e->code)) +
                             " (code " + std::to_string(e->code) + ", detail " + hex8(e->detail) +
                             ")",
                         e->code, addr);
      }
      const bool match = (expect == Expect::kRead && std::holds_alternative<ReadResp>(*f) &&
                          std::get<ReadResp>(*f).addr == addr) ||
                         (expect == Expect::kWrite && std::holds_alternative<WriteAck>(*f) &&
                          std::get<WriteAck>(*f).addr == addr) ||
                         (expect == Expect::kSnapshot && std::holds_alternative<SnapshotResp>(*f));
      if (match) return *f;
      ++counters_.unexpected_frames;
    }
  }
  throw BoardError("no answer to " + what + " after " + std::to_string(options_.attempts) +
                       " attempts of " + std::to_string(options_.response_timeout.count()) + " ms",
                   0, addr);
}

std::uint32_t BoardClient::read_register(std::uint8_t addr) {
  const auto f = transact(protocol::ReadReq{addr}, Expect::kRead, addr);
  return std::get<protocol::ReadResp>(f).data;
}

void BoardClient::write_register(std::uint8_t addr, std::uint32_t value) {
  (void)transact(protocol::WriteReq{addr, value}, Expect::kWrite, addr);
}

protocol::Window BoardClient::snapshot() {
  const auto f = transact(protocol::SnapshotReq{}, Expect::kSnapshot, regmap::kRegSnapSeq);
  return std::get<protocol::SnapshotResp>(f).window;
}

void BoardClient::set_streaming(bool on) {
  const std::uint32_t control = read_register(regmap::kRegControl);
  write_register(regmap::kRegControl, regmap::kControlStream.put(control, on ? 1u : 0u));
  if (on) decoder_.reset_sequence();
}

std::optional<protocol::Window> BoardClient::poll_telemetry(std::chrono::milliseconds timeout) {
  const auto deadline = transport_.now() + timeout;
  while (telemetry_.empty()) {
    auto f = next_frame(deadline);
    if (!f) return std::nullopt;
    if (auto* t = std::get_if<protocol::Telemetry>(&*f)) {
      queue_telemetry(t->window);
    } else {
      ++counters_.unexpected_frames;
    }
  }
  const auto w = telemetry_.front();
  telemetry_.pop_front();
  return w;
}

}  // namespace omniloc
