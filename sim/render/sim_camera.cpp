// The simulated camera's render worker (sim_robot.hpp, SimCamera).
#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

#include "omniloc_sim/sim_robot.hpp"

namespace omniloc::sim {

struct SimCamera::Worker {
  struct Job {
    std::int64_t k;
    Pose2 pose;
    RenderOptions options;
  };
  std::mutex mu;
  std::condition_variable cv;
  std::deque<Job> jobs;
  std::map<std::int64_t, cv::Mat> done;
  std::int64_t rendering = -1;  // the frame being rendered now, -1: none
  bool stop = false;
  std::thread thread;

  explicit Worker(const OmniRenderer& renderer) {
    thread = std::thread([this, &renderer] {
      std::unique_lock lock(mu);
      for (;;) {
        cv.wait(lock, [this] { return stop || !jobs.empty(); });
        if (stop) return;
        Job job = jobs.front();
        jobs.pop_front();
        rendering = job.k;
        lock.unlock();
        cv::Mat image = renderer.render(job.pose, job.options);
        lock.lock();
        rendering = -1;
        done.emplace(job.k, std::move(image));
        cv.notify_all();
      }
    });
  }
  ~Worker() {
    {
      std::lock_guard lock(mu);
      stop = true;
    }
    cv.notify_all();
    thread.join();
  }
};

SimCamera::SimCamera(const OmniRenderer& renderer, SimTruthLog& truth, double fps,
                     RenderOptions options)
    : renderer_(renderer),
      truth_(truth),
      period_ms_(1000.0 / fps),
      options_(std::move(options)),
      worker_(std::make_unique<Worker>(renderer)) {
  truth_.set_on_added([this](double t_ms) { on_truth(t_ms); });
}

SimCamera::~SimCamera() {
  truth_.set_on_added({});
}

void SimCamera::on_truth(double t_ms) {
  // Frame k can be rendered once the log holds a sample at or after its time (truth interpolates).
  for (; static_cast<double>(next_job_k_) * period_ms_ <= t_ms; ++next_job_k_) {
    const double t = static_cast<double>(next_job_k_) * period_ms_;
    if (stop_ms_ && t >= *stop_ms_) continue;
    const auto pose = truth_.truth(t);
    if (!pose) continue;
    RenderOptions o = options_;
    o.seed =
        options_.seed + static_cast<std::uint64_t>(next_job_k_);  // fresh sensor noise per frame
    {
      std::lock_guard lock(worker_->mu);
      worker_->jobs.push_back({next_job_k_, *pose, o});
    }
    worker_->cv.notify_all();
  }
}

std::optional<CameraFrame> SimCamera::poll(double now_ms) {
  const double lead_ms = delayed_ ? latency_ms_ : 0.0;  // no frame is handed over sooner
  const std::optional<double> latest_ms = truth_.latest_ms();
  if (!latest_ms) return std::nullopt;  // no truth yet: nothing exposed
  const double kd = std::floor(std::min(now_ms - lead_ms, *latest_ms) / period_ms_);
  if (kd < 0) return std::nullopt;
  auto k = static_cast<std::int64_t>(kd);
  // The newest frame handed over by now (the jitter can hold the last exposed one back).
  while (k > last_k_ && handover_ms(k) > now_ms) --k;
  if (k <= last_k_ || k >= next_job_k_) return std::nullopt;
  if (dropped(k)) {
    last_k_ = k;  // lost in the driver: the camera delivers nothing for it
    return std::nullopt;
  }
  const double t = static_cast<double>(k) * period_ms_;
  if (stop_ms_ && t >= *stop_ms_) return std::nullopt;
  std::unique_lock lock(worker_->mu);
  // Frames before k that were never polled are dropped, rendered or not.
  std::erase_if(worker_->jobs, [k](const Worker::Job& j) { return j.k < k; });
  const bool queued = worker_->done.count(k) != 0 || worker_->rendering == k ||
                      std::any_of(worker_->jobs.begin(), worker_->jobs.end(),
                                  [k](const Worker::Job& j) { return j.k == k; });
  last_k_ = k;
  if (!queued) {
    // Truth was missing for that frame when the log passed it (outside the kept span).
    worker_->done.erase(worker_->done.begin(), worker_->done.lower_bound(k + 1));
    return std::nullopt;
  }
  worker_->cv.wait(lock, [&] { return worker_->done.count(k) != 0; });
  cv::Mat image = std::move(worker_->done[k]);
  worker_->done.erase(worker_->done.begin(), worker_->done.lower_bound(k + 1));
  if (!delayed_) return CameraFrame{t, std::move(image), "sim", t};
  const double handover = handover_ms(k);
  return CameraFrame{handover, std::move(image), "host", handover};
}

}  // namespace omniloc::sim
