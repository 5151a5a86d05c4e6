// `omniloc-sim venues`: N venues from the sampler (omniloc_sim/venue.hpp), each a folder
// DIR/venue-<seed>/ with calib.png (the robot on a known spot, random heading), frame.png (a random
// pose) and truth.json (field, true optics, nominal camera, robot, spot, poses, look); a field that
// is not a shipped file is also written as DIR/field-<seed>.json. For measuring the calibration and
// the line extraction on cameras and venues they have never seen.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc_sim/venue.hpp"

namespace omniloc::cli {

namespace {

namespace fs = std::filesystem;

struct VenuesArgs {
  int count = 10;
  std::uint64_t seed = 1;
  std::string out;
};

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.close();
  if (!f) throw std::runtime_error(path.string() + ": cannot write");
}

void write_png(const fs::path& path, const cv::Mat& bgr) {
  if (!cv::imwrite(path.string(), bgr)) throw std::runtime_error(path.string() + ": cannot write");
}

// The output folder: created if missing; an existing file there is refused (not overwritten).
void prepare_out(const fs::path& out) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw std::runtime_error("--out " + out.string() + ": exists and is not a directory");
  fs::create_directories(out, ec);
  if (ec)
    throw std::runtime_error("--out " + out.string() + ": cannot create (" + ec.message() + ")");
}

// The field file a venue's truth names: the shipped name, or the spec written beside the venues.
std::string field_file(const sim::Venue& v, const fs::path& out) {
  if (v.field_shipped) return v.field_name;
  const std::string name = "field-" + std::to_string(v.seed) + ".json";
  write_text(out / name, config::write_keys(v.field.spec, field_spec_keys()).dump(2) + "\n");
  return name;
}

int run_venues(const VenuesArgs& a) {
  const fs::path out(a.out);
  prepare_out(out);
  std::printf("omniloc-sim venues: %d venues from seed %llu into %s\n", a.count,
              static_cast<unsigned long long>(a.seed), out.string().c_str());
  for (int i = 0; i < a.count; ++i) {
    const std::uint64_t seed = sim::venue_seed(a.seed, static_cast<std::uint64_t>(i));
    const sim::Venue v = sim::sample_venue(seed);
    const sim::VenueShots shots = sim::render_venue(v);
    const fs::path dir = out / ("venue-" + std::to_string(seed));
    fs::create_directories(dir);
    const std::string field = field_file(v, out);
    write_png(dir / "calib.png", shots.calib);
    write_png(dir / "frame.png", shots.frame);
    write_text(dir / "truth.json", sim::venue_truth_json(v, shots, field));
    std::printf("venue %d/%d seed %llu: %s%s, %s mirror, %dx%d, %zu rods, spot %s -> %s\n", i + 1,
                a.count, static_cast<unsigned long long>(seed), v.field_name.c_str(),
                v.lab ? " (lab)" : "", sim::mirror_profile_name(v.optics.profile),
                v.optics.width_px, v.optics.height_px, v.optics.rods.size(),
                shots.spot.name.c_str(), dir.string().c_str());
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

Subcommand add_venues(CLI::App& program) {
  CLI::App* app = program.add_subcommand("venues",
                                         "Sampled cameras, robots and venues: per venue calib.png, "
                                         "frame.png and truth.json (sim/README.md).");
  auto a = std::make_shared<VenuesArgs>();
  add_number_option(*app, "--count", a->count, "how many venues", 1, 100000);
  add_number_option(*app, "--seed", a->seed,
                    "run seed (venue i's seed is derived from it and i, and printed)");
  app->add_option("--out", a->out, "output folder (created if missing)")->required();
  return {app, [a] { return run_venues(*a); }};
}

}  // namespace omniloc::cli
