// Host frame-parsing throughput: omniloc::protocol::FrameDecoder against a naive parser (a deque of
// bytes, a copy of every candidate frame, a bitwise CRC), on the same byte stream: telemetry frames
// with 1 % of the bytes replaced by garbage, fed in 62-byte chunks (the payload of a full-speed USB
// packet; at high speed packets are 510 bytes and the decoder's per-call cost matters even less).
// Prints MB/s and frames/s of both and the ratio.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <deque>
#include <map>
#include <random>
#include <string>

#include "omniloc/protocol.hpp"

namespace {

using namespace omniloc;

const std::vector<std::uint8_t>& stream() {
  static const std::vector<std::uint8_t> s = [] {
    std::mt19937 rng(7);
    std::vector<std::uint8_t> out;
    for (std::uint32_t seq = 1; seq <= 20000; ++seq) {
      protocol::Window w{seq, seq * 397'500u, {}, static_cast<std::uint8_t>(seq & 0xF), 0};
      for (auto& c : w.count) c = static_cast<std::int32_t>(rng() % 2001) - 1000;
      protocol::encode_into(protocol::Telemetry{w}, out);
    }
    std::uniform_int_distribution<std::size_t> at(0, out.size() - 1);
    for (std::size_t i = 0; i < out.size() / 100; ++i)
      out[at(rng)] = static_cast<std::uint8_t>(rng());
    return out;
  }();
  return s;
}

// ---- The naive reference ----
std::uint16_t crc_bitwise(const std::vector<std::uint8_t>& bytes) {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t b : bytes) {
    crc ^= static_cast<std::uint16_t>(b << 8);
    for (int i = 0; i < 8; ++i)
      crc = (crc & 0x8000) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021)
                           : static_cast<std::uint16_t>(crc << 1);
  }
  return crc;
}

class NaiveParser {
 public:
  std::size_t feed(const std::uint8_t* p, std::size_t n) {
    std::size_t frames = 0;
    buf_.insert(buf_.end(), p, p + n);
    while (true) {
      while (!buf_.empty() && buf_.front() != 0xA5) buf_.pop_front();
      if (buf_.size() < 3) return frames;
      const auto body = protocol::body_bytes(buf_[2]);
      if (!body || buf_[1] != *body + 1) {
        buf_.pop_front();
        continue;
      }
      const std::size_t total = *body + 5;
      if (buf_.size() < total) return frames;
      std::vector<std::uint8_t> covered(buf_.begin() + 1,
                                        buf_.begin() + static_cast<std::ptrdiff_t>(total - 2));
      const auto crc = static_cast<std::uint16_t>((buf_[total - 2] << 8) | buf_[total - 1]);
      if (crc_bitwise(covered) != crc) {
        buf_.pop_front();
        continue;
      }
      std::vector<std::uint8_t> body_bytes(covered.begin() + 2, covered.end());
      benchmark::DoNotOptimize(protocol::decode_body(covered[1], body_bytes));
      buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(total));
      ++frames;
    }
  }

 private:
  std::deque<std::uint8_t> buf_;
};

constexpr std::size_t kChunk = 62;

void BM_FrameDecoder(benchmark::State& state) {
  const auto& s = stream();
  std::size_t frames = 0;
  for (auto _ : state) {
    protocol::FrameDecoder d;
    for (std::size_t at = 0; at < s.size(); at += kChunk) {
      d.feed(std::span(s).subspan(at, std::min(kChunk, s.size() - at)));
      while (auto f = d.next()) {
        benchmark::DoNotOptimize(*f);
        ++frames;
      }
    }
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * s.size()));
  state.counters["frames"] = static_cast<double>(frames) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_FrameDecoder)->Unit(benchmark::kMillisecond);

void BM_NaiveParser(benchmark::State& state) {
  const auto& s = stream();
  std::size_t frames = 0;
  for (auto _ : state) {
    NaiveParser p;
    for (std::size_t at = 0; at < s.size(); at += kChunk)
      frames += p.feed(s.data() + at, std::min(kChunk, s.size() - at));
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * s.size()));
  state.counters["frames"] = static_cast<double>(frames) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_NaiveParser)->Unit(benchmark::kMillisecond);

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> ns_per_stream;
  std::map<std::string, double> frames;
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration) continue;
      ns_per_stream[r.benchmark_name()] = r.GetAdjustedCPUTime() * 1e6;  // reported in ms
      frames[r.benchmark_name()] = r.counters.at("frames");
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_stream;
  const auto naive = m.find("BM_NaiveParser");
  const double bytes = static_cast<double>(stream().size());
  for (const auto& [name, ns] : m) {
    std::printf("%-16s %8.1f MB/s  %10.0f frames/s  (%.0f frames accepted of 20000)", name.c_str(),
                bytes / ns * 1e3, reporter.frames[name] / ns * 1e9, reporter.frames[name]);
    if (naive != m.end()) std::printf("  %.1fx the naive reference", naive->second / ns);
    std::printf("\n");
  }
  benchmark::Shutdown();
  return 0;
}
