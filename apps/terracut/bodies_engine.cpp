#include "bodies_engine.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "terracut/core/error.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_csv.hpp"
#include "terracut/bullet/terrain_world.hpp"
#endif

namespace terracut::apps {

std::string bodies_engine_unavailable_message() {
  return "bodies: this terracut was built without Bullet (libbullet-dev was not found when it "
         "was configured), so the scenario's rigid bodies cannot be simulated; install "
         "libbullet-dev and rebuild, or remove the `bodies:` list";
}

#ifdef TERRACUT_HAVE_BULLET
namespace {

class BodiesEngine final : public haptics::LoopEngine {
 public:
  BodiesEngine(std::vector<BodySpec> bodies, BodiesEngineOptions options)
      : bodies_(std::move(bodies)), options_(std::move(options)) {}

  void attach(Simulation& sim) override {
    world_ = std::make_unique<bullet::TerrainWorld>(sim, bodies_);
    // Shapes and sizes never change: keep them for the viewer's frames.
    half_extents_.clear();
    for (const BodySpec& b : bodies_) half_extents_.push_back(half_extents_m(b));
    if (!options_.csv_path.empty()) {
      csv_ = std::make_unique<bullet::BodiesCsvWriter>(options_.csv_path);
      csv_->write_step(*world_);  // the initial state, t = 0
    }
  }

  Vec3 after_cut(const StepOutput& out) noexcept override {
    if (!world_) return {};
    world_->step(out);
    if (csv_) csv_->write_step(*world_);
    const bullet::WorldStepInfo& info = world_->last();
    peak_tool_force_n_ = std::max(peak_tool_force_n_, length(info.tool_force_n));
    if (info.tool_contact_points > 0) ++ticks_touching_;
    ++steps_;
    physics_sum_s_ += info.physics_s;
    physics_max_s_ = std::max(physics_max_s_, info.physics_s);
    return info.tool_force_n;
  }

  void lifted() noexcept override {
    if (world_) world_->lift_tool();
  }

  void fill_frame(haptics::ViewFrame& frame) const noexcept override {
    const int total = world_ ? world_->body_count() : 0;
    const int n = std::min(total, haptics::kMaxViewBodies);
    for (int i = 0; i < n; ++i) {
      const bullet::BodyState s = world_->body_state(i);
      haptics::ViewBody& v = frame.bodies[std::size_t(i)];
      v.shape = bodies_[std::size_t(i)].shape;
      v.half_extents_m = half_extents_[std::size_t(i)];
      v.position_m = s.position_m;
      v.orientation = s.orientation;
      v.active = s.active;
    }
    frame.body_count = n;
    frame.body_total = total;
  }

  void detach() noexcept override {
    if (!world_) return;
    try {
      summary_ = make_summary();
    } catch (...) {
      summary_ = "{}";  // out of memory: the summary is the least of the problems
    }
    world_.reset();
  }

  void finish() override {
    if (csv_) csv_->close();
  }

  std::string summary_key() const override { return "bodies"; }
  std::string summary_json() const override { return world_ ? make_summary() : summary_; }

 private:
  std::string make_summary() const {
    nlohmann::json j;
    j["count"] = bodies_.size();
    j["engine"] = "bullet";
    if (options_.csv_path.empty())
      j["csv"] = nullptr;
    else
      j["csv"] = options_.csv_path.filename().string();
    j["peak_tool_force_n"] = peak_tool_force_n_;
    j["ticks_touching_tool"] = ticks_touching_;
    j["steps"] = steps_;
    j["physics_us"] = {{"mean", steps_ > 0 ? 1e6 * physics_sum_s_ / double(steps_) : 0.0},
                       {"max", 1e6 * physics_max_s_}};
    j["height_bounds_m"] = {world_->bounds().min_height_m, world_->bounds().max_height_m};
    j["samples_clamped_to_bounds"] = world_->bounds().clamped_total;
    nlohmann::json final_states = nlohmann::json::array();
    for (int i = 0; i < world_->body_count(); ++i) {
      const bullet::BodyState s = world_->body_state(i);
      final_states.push_back({{"name", bodies_[std::size_t(i)].name},
                              {"position_m", {s.position_m.x, s.position_m.y, s.position_m.z}}});
    }
    j["final"] = final_states;
    return j.dump();
  }

  std::vector<BodySpec> bodies_;
  BodiesEngineOptions options_;
  std::vector<Vec3> half_extents_;
  std::unique_ptr<bullet::TerrainWorld> world_;
  std::unique_ptr<bullet::BodiesCsvWriter> csv_;
  std::string summary_ = "{}";
  double peak_tool_force_n_ = 0.0;
  std::int64_t ticks_touching_ = 0;
  std::int64_t steps_ = 0;
  double physics_sum_s_ = 0.0;
  double physics_max_s_ = 0.0;
};

}  // namespace

bool bodies_engine_available() { return true; }

std::unique_ptr<haptics::LoopEngine> make_bodies_engine(std::vector<BodySpec> bodies,
                                                        const BodiesEngineOptions& options) {
  return std::make_unique<BodiesEngine>(std::move(bodies), options);
}
#else
bool bodies_engine_available() { return false; }

std::unique_ptr<haptics::LoopEngine> make_bodies_engine(std::vector<BodySpec>,
                                                        const BodiesEngineOptions&) {
  throw InputError(bodies_engine_unavailable_message());
}
#endif

}  // namespace terracut::apps
