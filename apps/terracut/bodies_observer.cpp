#include "bodies_observer.hpp"

#include <nlohmann/json.hpp>

#include "terracut/core/error.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_csv.hpp"
#include "terracut/bullet/terrain_world.hpp"
#endif

namespace terracut::cli {

#ifdef TERRACUT_HAVE_BULLET
namespace {

class BodiesObserver final : public io::RunObserver {
 public:
  explicit BodiesObserver(std::vector<BodySpec> bodies) : bodies_(std::move(bodies)) {}

  void start(Simulation& sim, const std::filesystem::path& out_dir) override {
    world_ = std::make_unique<bullet::TerrainWorld>(sim, bodies_);
    csv_ = std::make_unique<bullet::BodiesCsvWriter>(out_dir / "bodies.csv");
    csv_->write_step(*world_);  // the initial state, t = 0
  }
  void lifted() override { world_->lift_tool(); }
  void stepped(const StepOutput& out) override {
    world_->step(out);
    csv_->write_step(*world_);
    physics_s_ = std::max(physics_s_, world_->last().physics_s);
    const Vec3 f = world_->last().tool_force_n;
    peak_tool_force_n_ = std::max(peak_tool_force_n_, length(f));
  }
  void finish() override { csv_->close(); }
  std::string summary_key() const override { return "bodies"; }
  std::string summary_json() const override {
    nlohmann::json j;
    j["count"] = bodies_.size();
    j["csv"] = "bodies.csv";
    j["peak_tool_force_n"] = peak_tool_force_n_;
    j["height_bounds_m"] = {world_->bounds().min_height_m, world_->bounds().max_height_m};
    j["samples_clamped_to_bounds"] = world_->bounds().clamped_total;
    nlohmann::json final_states = nlohmann::json::array();
    for (int i = 0; i < world_->body_count(); ++i) {
      const bullet::BodyState s = world_->body_state(i);
      final_states.push_back({{"name", bodies_[size_t(i)].name},
                              {"position_m", {s.position_m.x, s.position_m.y, s.position_m.z}}});
    }
    j["final"] = final_states;
    return j.dump();
  }

 private:
  std::vector<BodySpec> bodies_;
  std::unique_ptr<bullet::TerrainWorld> world_;
  std::unique_ptr<bullet::BodiesCsvWriter> csv_;
  double physics_s_ = 0.0;
  double peak_tool_force_n_ = 0.0;
};

}  // namespace

std::unique_ptr<io::RunObserver> make_bodies_observer(const std::vector<BodySpec>& bodies) {
  return std::make_unique<BodiesObserver>(bodies);
}
#else
std::unique_ptr<io::RunObserver> make_bodies_observer(const std::vector<BodySpec>&) {
  throw InputError(
      "bodies: this terracut was built without Bullet (libbullet-dev), so rigid bodies cannot be "
      "simulated; install it and rebuild");
}
#endif

}  // namespace terracut::cli
