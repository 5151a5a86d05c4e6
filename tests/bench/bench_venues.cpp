// Generality of the camera front end (issue [1/4] item 4): over sampled venues (the realistic
// renderer's venue sampler: cameras, mirrors, robots, carpets, light, fields), `calibrate` at a
// known spot with the heading unknown, then `locate` a second frame at a random pose with that
// camera. Printed: the rates against the goal, the failures by step, the seeds that failed, and
// the same locate with each venue's true camera in the same run (the reference: what the front
// end would reach with a perfect calibration). VENUES_COUNT (default 300) and VENUES_SEED
// (default 2026) choose the venues; every venue's seed is printed, and VENUES_SEEDS (a comma list
// of printed venue seeds) re-runs those venues alone.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../host/venue_trial.hpp"

int main() {
  using namespace omniloc;
  const char* count_env = std::getenv("VENUES_COUNT");
  const char* seed_env = std::getenv("VENUES_SEED");
  const int count = count_env != nullptr ? std::atoi(count_env) : 300;
  const std::uint64_t seed = seed_env != nullptr ? std::strtoull(seed_env, nullptr, 10) : 2026;
  if (count <= 0 || count > 100000) {
    std::fprintf(stderr, "bench_venues: VENUES_COUNT must be 1..100000 (got %d)\n", count);
    return 2;
  }
  std::vector<std::uint64_t> venues;
  if (const char* list = std::getenv("VENUES_SEEDS"); list != nullptr) {
    std::istringstream in(list);
    for (std::string item; std::getline(in, item, ',');) {
      char* end = nullptr;
      const std::uint64_t v = std::strtoull(item.c_str(), &end, 10);
      if (item.empty() || end == nullptr || *end != '\0') {
        std::fprintf(stderr,
                     "bench_venues: VENUES_SEEDS must be a comma list of venue seeds (got '%s')\n",
                     item.c_str());
        return 2;
      }
      venues.push_back(v);
    }
    std::printf("bench_venues: the %zu venues of VENUES_SEEDS\n", venues.size());
  } else {
    for (int i = 0; i < count; ++i)
      venues.push_back(sim::venue_seed(seed, static_cast<std::uint64_t>(i)));
    std::printf("bench_venues: %d venues of seed %llu\n", count,
                static_cast<unsigned long long>(seed));
  }
  const auto t0 = std::chrono::steady_clock::now();
  int calibrated = 0, calib_good = 0, located = 0, wild = 0, ref_located = 0;
  std::map<std::string, int> by_step;
  std::vector<std::uint64_t> failed;
  const int n_venues = static_cast<int>(venues.size());
  for (int i = 0; i < n_venues; ++i) {
    const test::VenueOutcome o = test::run_venue(venues[static_cast<std::size_t>(i)]);
    std::printf("[%3d/%d] ", i + 1, n_venues);
    test::print_outcome(o);
    std::fflush(stdout);
    calibrated += o.calibrated;
    calib_good += o.calib_good;
    located += o.located_good();
    wild += o.wild();
    ref_located += o.reference_good();
    if (!o.calibrated)
      ++by_step[o.calib_step];
    else if (!o.calib_good)
      ++by_step["calibrated outside the goal"];
    else if (!o.located_good())
      ++by_step[o.located.usable ? "located outside the goal" : "locate: no measurement"];
    if (!o.calib_good || !o.located_good()) failed.push_back(o.seed);
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto pct = [n_venues](int n) { return 100.0 * n / n_venues; };
  std::printf("\ncalibrated (a camera written): %d of %d (%.1f %%)\n", calibrated, n_venues,
              pct(calibrated));
  std::printf(
      "calibrated within the goal (rms < 2 px, centre within 2 px): %d (%.1f %%; goal 97 %%)\n",
      calib_good, pct(calib_good));
  std::printf(
      "second frame located within 5 cm and 2 deg (pose or twin, below E_TH): %d (%.1f %%; goal 95 "
      "%%)\n",
      located, pct(located));
  std::printf("accepted more than 20 cm off: %d (goal 0)\n", wild);
  std::printf(
      "reference, the same frames with the true cameras: located %d (%.1f %%); ratio calibrated / "
      "true %.2f\n",
      ref_located, pct(ref_located),
      ref_located > 0 ? static_cast<double>(located) / ref_located : 0.0);
  std::printf("failures by step:");
  for (const auto& [step, n] : by_step) std::printf(" %s %d;", step.c_str(), n);
  std::printf("\nseeds that failed:");
  for (const auto f : failed) std::printf(" %llu", static_cast<unsigned long long>(f));
  std::printf("\n%.0f s\n", s);
  return 0;
}
