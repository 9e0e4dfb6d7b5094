#include "realtime_observer.hpp"

#include <nlohmann/json.hpp>

#include "terracut/haptics/pacer.hpp"

namespace terracut::cli {

namespace {

nlohmann::json to_json_us(const haptics::TimeStats& s) {
  return {{"p50_us", s.p50_s * 1e6}, {"p99_us", s.p99_s * 1e6}, {"max_us", s.max_s * 1e6},
          {"mean_us", s.mean_s * 1e6}, {"count", s.count}};
}

class RealtimeObserver final : public io::RunObserver {
 public:
  explicit RealtimeObserver(double rate_hz) : pacer_(haptics::PacerSettings{.rate_hz = rate_hz}) {}

  void start(Simulation&, const std::filesystem::path&) override {}
  // Each step starts on its deadline: the first one anchors the schedule.
  void before_step() override {
    if (!started_) {
      pacer_.start();
      started_ = true;
    } else {
      pacer_.wait_next();
    }
  }
  void stepped(const StepOutput& out) override { pacer_.record_compute(out.timers.total_s); }
  std::string summary_key() const override { return "realtime"; }
  std::string summary_json() const override {
    const haptics::LoopStats s = pacer_.stats();
    nlohmann::json j;
    j["rate_hz"] = s.rate_hz;
    j["period_us"] = 1e6 / s.rate_hz;
    j["ticks"] = s.ticks;
    j["missed_deadlines"] = s.missed_deadlines;
    j["skipped_slots"] = s.skipped_slots;
    j["step_time"] = to_json_us(s.compute);
    j["period_jitter"] = to_json_us(s.period_jitter);
    j["wake_latency"] = to_json_us(s.wake_latency);
    return j.dump();
  }

 private:
  haptics::Pacer pacer_;
  bool started_ = false;
};

}  // namespace

std::unique_ptr<io::RunObserver> make_realtime_observer(double rate_hz) {
  return std::make_unique<RealtimeObserver>(rate_hz);
}

}  // namespace terracut::cli
